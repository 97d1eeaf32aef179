// Rough bake cost before baking (`cellbake info`, `bake --dry-run`): seconds
// and bytes per cell from one measured bake, scaled by face size, threads and
// the model's triangle count.
// Measured: the demo (2 M-triangle plant, 63 cells of 4 m, 512² faces, default
// samples, 2 threads on a 2-core x86 VM): 137 thread-s in its stages → 2.2
// core-seconds per cell; 2.1 MB stored, 34 KB per cell (fresh-clone
// scripts/demo.sh with the sample defaults of issue #36, December 2026).
// Other models cost less or more per cell, roughly with a power of their
// triangle count T (16 cells each of info's suggested bake, one thread, user +
// system CPU relative to the demo's cells at the same time; docs/benchmark-history.md
// "The bake estimate"): duck.dae 4 k triangles 0.26, the IFC house 36 k 0.29,
// a generated house 100 k 0.52, plant 100 k 0.67, plant 500 k 0.75, the
// 12.7 M plant 2.6 (its BVH build included); bytes per cell 0.06, 0.05, 0.08,
// 0.15, 0.37 and 5.3 (measured against the demo's earlier 6.3 s and 150 KB;
// with today's defaults the 12.7 M plant costs 1.4-1.9 times the demo per
// 4 m cell and 1.1 per 1 m cell: the estimate errs high for big models). Hence time × (T / 2 M)^0.25 below 2 M and ^0.5 above,
// bytes × (T / 2 M)^0.5 below (at least 0.05) and ^0.9 above. Open scenes with
// much sky cost less (a generated city of 300 k: 0.23 where 0.62 is
// estimated). A guide within about a factor of two, not a promise.
#pragma once

#include <cstdint>
#include <string>

namespace cellbake {

inline constexpr double kMeasuredCoreSecondsPerCell = 2.2;  // the demo, at 512² faces
inline constexpr double kMeasuredBytesPerCell = 34e3;       // the demo, at 512² faces
inline constexpr double kMeasuredModelTriangles = 2e6;      // the demo plant's

struct BakeEstimate {
  double core_seconds_per_cell = 0;
  double seconds = 0;  // wall seconds for all cells on `threads` threads
  double bytes_per_cell = 0;
  double bytes = 0;
};

// Cost scales with the face's pixel count (face_size / 512)² and with the
// model's size as above (`model_triangles` 0: taken as the demo's); the wall
// time divides the core-seconds by `threads` (≥ 1).
BakeEstimate estimate_bake(std::uint64_t cells, int face_size, int threads, std::uint64_t model_triangles);

// "45 s", "12 min", "3.1 h".
std::string duration_text(double seconds);

}  // namespace cellbake
