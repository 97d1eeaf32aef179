// From a few measured cells to a whole bake (`bake --dry-run --measure K`):
// pure arithmetic. A cell's stages run one after another on one thread and
// the bake keeps `threads` cells in flight, so equal cells of c CPU-seconds
// take ceil(cells / threads) * c of wall time on one machine; on S Slurm
// shards (cellbake submit: cost-balanced subsets) of T threads each, the
// largest shard holds ceil(cells / S) cells. Every thread is assumed to have a
// core of its own (the measured CPU-seconds already include what the process
// does besides cells, spread over the measured cells).
#pragma once

#include <cstdint>
#include <vector>

namespace cellbake {

// What baking `cells` measured cells cost: the bake process's CPU time (user +
// system) and the bytes stored.
struct MeasuredCost {
  std::uint64_t cells = 0;
  double cpu_seconds = 0;
  double bytes = 0;
};

struct ShardProjection {
  int shards = 0;                      // as asked
  int threads_per_shard = 0;
  std::uint64_t cells_per_shard = 0;   // the largest shard's
  double wall_seconds = 0;             // the largest shard's bake
};

struct BakeProjection {
  std::uint64_t cells = 0;
  double cpu_seconds_per_cell = 0, bytes_per_cell = 0;
  double cpu_seconds = 0;   // every cell, one after another
  double bytes = 0;         // every cell's
  int threads = 0;
  double wall_seconds = 0;  // one machine, `threads` threads
  std::vector<ShardProjection> shards;
};

// Projects `measured` (cells > 0, finite non-negative figures) to `cells`
// cells on one machine of `threads` (>= 1) threads and on each of
// `shard_counts` (each >= 1) shards of `threads_per_shard` (>= 1) threads.
// Throws std::invalid_argument for anything outside those ranges.
BakeProjection project_bake(const MeasuredCost& measured, std::uint64_t cells, int threads,
                            const std::vector<int>& shard_counts, int threads_per_shard);

}  // namespace cellbake
