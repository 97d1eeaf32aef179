// The main() of a benchmark program that is a plain command (not Google
// Benchmark): runs `run` and turns an exception into a message naming the
// program and exit code 1. Header-only.
#pragma once

#include <cstdio>
#include <exception>

namespace cellbake {

inline int run_bench_program(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace cellbake
