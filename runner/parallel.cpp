#include "runner/parallel.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>
#include <thread>

#include "stages/tsan_handoff.h"

namespace cellbake {
namespace {

// TSan tokens at fixed addresses: a body reads them before it has acquired
// anything (its own closure is part of what TBB hands over).
const char fork_token = 0, join_token = 0;

}  // namespace

ParallelFor tbb_parallel_for() {
  return [](std::size_t n, const std::function<void(std::size_t)>& fn) {
    // fork: the caller's writes happen before every fn(i); join: every fn(i)
    // happens before parallel_for returns (stages/tsan_handoff.h). TBB keeps a
    // reference to `body`, on this stack, and workers read its captures: build
    // it before the fork, or its construction is a write TSan sees racing them.
    const auto body = [&](std::size_t i) {
      tsan::after(&fork_token);
      fn(i);
      tsan::before(&join_token);
    };
    tsan::before(&fork_token);
    tbb::parallel_for(std::size_t(0), n, body);
    tsan::after(&join_token);
  };
}

int worker_threads(int requested) {
  return requested > 0 ? requested : int(std::max(1u, std::thread::hardware_concurrency()));
}

int drawing_worker_threads(int requested) {
  const int threads = worker_threads(requested);
  if (!std::getenv("LP_NUM_THREADS")) setenv("LP_NUM_THREADS", threads > 1 ? "1" : "2", 1);
  return threads;
}

}  // namespace cellbake
