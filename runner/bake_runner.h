// The bake runner: the only code that schedules cells. A oneTBB flow graph
// runs cells x stages (cull_box -> sample -> depth_mesh + simplify -> encode ->
// write) with one GL context per worker thread for the sample stage and a
// single serial writer that commits each cell in its own transaction.
#pragma once

#include <cstdint>
#include <string>

#include "pipeline/bake_config.h"

namespace cellbake {

struct BakeOptions {
  int threads = 0;              // 0 = all cores
  std::string cells;            // selection like "1-10,15" ("" = all)
  bool force = false;           // recompute even cells whose stored hash matches
  int shard_index = 0, shard_count = 1;  // bake only this shard's cells
  bool quiet = false;           // no progress output
  bool verbose = false;         // a line per written cell: status, stage seconds, samples, triangles, bytes
};

struct BakeSummary {
  std::uint64_t cells_selected = 0;
  std::uint64_t cells_up_to_date = 0;  // skipped: stored input hash matches
  std::uint64_t cells_baked = 0;
  std::uint64_t cells_failed = 0;
  std::uint64_t cull_reused = 0;       // cull-box results reused from the database
  double seconds = 0;
};

// Bakes the configured cells into config.database. Failed cells are recorded
// (status + message) and do not stop the others. Deterministic cell rows
// whatever `threads` is. Throws only for setup errors (bad store, bad config).
BakeSummary run_bake(const BakeConfig& config, const BakeOptions& options);

}  // namespace cellbake
