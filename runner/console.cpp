#include "runner/console.h"

#include <atomic>

namespace cellbake {
namespace {

std::atomic<Verbosity> g_verbosity{Verbosity::normal};

}  // namespace

void set_verbosity(Verbosity v) { g_verbosity = v; }
Verbosity verbosity() { return g_verbosity; }

}  // namespace cellbake
