// Rough bake cost before baking (`cellbake info`, `bake --dry-run`): seconds
// and bytes per cell from one measured bake, scaled by face size and threads.
// Measured: the demo (2 M-triangle plant, 63 cells of 4 m, 512² faces, default
// samples, 2 threads on a 2-core x86 VM): 197 s wall → 6.3 core-seconds per
// cell (fresh-clone scripts/demo.sh, December 2026; 318 s and 10.1 before
// the sample-choice speed-ups); ~150 KB stored per cell since far geometry
// is stored as triangle numbers (docs/benchmarks.md). A model's cost per cell depends on what a cell
// sees, so treat the figures as a factor-of-two guide.
#pragma once

#include <cstdint>
#include <string>

namespace cellbake {

inline constexpr double kMeasuredCoreSecondsPerCell = 6.3;   // at 512² faces
inline constexpr double kMeasuredBytesPerCell = 150e3;       // at 512² faces

struct BakeEstimate {
  double core_seconds_per_cell = 0;
  double seconds = 0;  // wall seconds for all cells on `threads` threads
  double bytes_per_cell = 0;
  double bytes = 0;
};

// Cost scales with the face's pixel count (face_size / 512)²; the wall time
// divides the core-seconds by `threads` (≥ 1).
BakeEstimate estimate_bake(std::uint64_t cells, int face_size, int threads);

// "45 s", "12 min", "3.1 h".
std::string duration_text(double seconds);

}  // namespace cellbake
