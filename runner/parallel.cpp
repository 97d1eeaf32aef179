#include "runner/parallel.h"

#include <tbb/parallel_for.h>

namespace cellbake {

ParallelFor tbb_parallel_for() {
  return [](std::size_t n, const std::function<void(std::size_t)>& fn) {
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) { fn(i); });
  };
}

}  // namespace cellbake
