// The tsan job's check of itself (scripts/sanitize.sh tsan): with
// tests/sanitizers/tsan.supp and stages/tsan_handoff.h, ThreadSanitizer must
// still report a race in cellbake code that runs inside TBB tasks, and none
// where the code is correct. Each mode writes one counter from many bodies:
//   tsan_canary parallel_for|flow_graph   a plain int: a race TSan must report
//   tsan_canary clean                     the same through std::atomic: no report
#include <tbb/flow_graph.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "runner/parallel.h"

namespace {

int plain_counter = 0;
std::atomic<int> atomic_counter{0};

void slow_body(bool racy) {
  if (racy)
    plain_counter = plain_counter + 1;
  else
    ++atomic_counter;
  std::this_thread::sleep_for(std::chrono::milliseconds(2));  // lets another thread take the next body
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "parallel_for" || mode == "clean") {
    cellbake::tbb_parallel_for()(64, [&](std::size_t) { slow_body(mode != "clean"); });
  } else if (mode == "flow_graph") {
    tbb::flow::graph g;
    tbb::flow::function_node<int, int> node(g, tbb::flow::unlimited, [](int v) {
      slow_body(true);
      return v;
    });
    for (int i = 0; i < 64; ++i) node.try_put(i);
    g.wait_for_all();
  } else {
    std::fprintf(stderr, "usage: tsan_canary parallel_for|flow_graph|clean\n");
    return 2;
  }
  std::printf("%d\n", plain_counter + atomic_counter.load());
  return 0;
}
