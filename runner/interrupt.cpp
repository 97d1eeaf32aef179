#include "runner/interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <cstring>

namespace cellbake {
namespace {

const char* g_message = "";

extern "C" void on_interrupt(int) {
  (void)!::write(STDERR_FILENO, "\n", 1);
  (void)!::write(STDERR_FILENO, g_message, std::strlen(g_message));
  (void)!::write(STDERR_FILENO, "\n", 1);
  ::_exit(130);
}

}  // namespace

void exit_on_interrupt(const char* message) {
  g_message = message;
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
}

}  // namespace cellbake
