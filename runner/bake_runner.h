// The bake runner: the only code that schedules cells. A oneTBB flow graph
// runs cells through four nodes: cull_box -> sample (at most `threads` at
// once, each worker with its own cube sampler: an Embree tracer or a GL
// context) -> depth_mesh, far_choice and encode in one node (the far choice
// meshes and simplifies faces on demand) -> a single serial writer that
// commits each cell in its own transaction.
#pragma once

#include <cstdint>
#include <string>

#include <vector>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/floor_regions.h"

namespace cellbake {

class GeometryStore;

struct BakeOptions {
  int threads = 0;              // 0 = all cores
  std::string cells;            // selection like "1-10,15" ("" = all)
  bool force = false;           // recompute even cells whose stored hash matches
  int shard_index = 0, shard_count = 1;  // bake only this shard's cells
  bool quiet = false;           // no progress output
  bool verbose = false;         // a line per written cell: status, stage seconds, samples, triangles, bytes
  // The store is checked before anything is read from it: its row counts
  // against the ones ingest recorded, or with check_store the full check
  // (content hash recomputed, R-tree, every chunk decoded; storage/store_check.h).
  bool check_store = false;
};

struct BakeSummary {
  std::uint64_t cells_selected = 0;
  std::uint64_t cells_up_to_date = 0;  // skipped: stored input hash matches
  std::uint64_t cells_baked = 0;
  std::uint64_t cells_failed = 0;
  std::uint64_t cull_reused = 0;       // cull-box results reused from the database
  std::uint64_t cells_without_far_field = 0;  // baked cells whose far field came out empty
  std::string sample_backend;  // who rendered the samples: "egl", "embree", ... ("" when nothing was sampled)
  std::string sample_device;   // its CubeSampler::device(), e.g. a GPU's name, "llvmpipe (...)" or "CPU"
  double seconds = 0;
};

// What a bake would do, before it writes anything (run_bake's first step and
// `bake --dry-run`): the config validated, its up axis resolved against the
// store's (`up_note`: the note or warning to print, else ""), regions checked
// against the model's bounds, the effective near budget (near.budget_fraction
// of a small model), and the selected cells (--cells, shard). A floor
// selection (config.floors) becomes the regions first (pipeline/floor_regions.h),
// so cell ids and hashes are those of the equivalent --region bake. Throws on
// the errors run_bake would throw for.
struct BakePlan {
  BakeConfig config;                // with `up`, `near_budget` and the regions as the bake will use them (floors: none)
  std::string up_note;
  FloorRegions floors;              // what config.floors became (empty without floors)
  std::uint64_t model_triangles = 0;
  std::uint64_t cells_total = 0;    // the configuration's cells
  std::vector<CellSpec> cells;      // this run's selection
};
BakePlan plan_bake(const BakeConfig& config, const BakeOptions& options, const GeometryStore& store);

// Bakes the configured cells into config.database. Failed cells are recorded
// (status + message) and do not stop the others. Deterministic cell rows
// whatever `threads` is. Throws only for setup errors (bad store, bad config;
// a store that fails require_sound_store).
BakeSummary run_bake(const BakeConfig& config, const BakeOptions& options);

}  // namespace cellbake
