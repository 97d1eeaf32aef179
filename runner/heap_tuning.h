// Process-wide allocator settings for bakes (and the benchmarks that time
// their stages, so they measure what a bake runs).
#pragma once

namespace cellbake {

// glibc hands blocks above its (adaptive) mmap threshold back to the kernel
// on free, and a bake frees and reallocates tens of megabytes per cube map
// and face (hit arrays, dense depth meshes, simplifier grids): the kernel
// then zeroes every page again (0.79 M page faults, 2-3 s of system time in a
// 63-cell one-sample demo bake; docs/benchmark-history.md). Keeps blocks up to
// 32 MiB (glibc's largest threshold) in the heap and trims it only past
// 512 MiB, so they are reused. Call once, first thing in main.
void keep_large_blocks_in_the_heap();

}  // namespace cellbake
