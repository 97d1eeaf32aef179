// `cellbake bake ... --dry-run [--measure K [--shards S,...]]`: what a bake
// would do, writing nothing — the cells it selects (with the floors a floors
// bake turns into regions, each as the --region it equals), the effective near
// budget and the guessed time and bytes (pipeline/bake_estimate.h); with
// --measure, K cells chosen stratified over the selection
// (pipeline/stratified_cells.h) baked for real into a temporary database
// (runner/measured_estimate.h) and the whole selection projected from them
// on --threads threads and on S Slurm shards (pipeline/bake_projection.h).
#pragma once

#include <string>
#include <vector>

#include "runner/bake_command_options.h"
#include "runner/bake_runner.h"

namespace cellbake {

struct DryRunRequest {
  int measure = 0;                  // cells to bake and measure (0: guess from the demo's figures only)
  std::vector<int> shards{10, 100};  // Slurm shard counts to project onto (with measure)
  bool json = false;
};

// Prints the dry run for `config` (built from `options` by
// bake_config_from_options) to stdout, as text or one JSON object. Throws
// what plan_bake throws, and what measure_cells throws. When Ctrl-C stops the
// measurement, prints that nothing was written and exits with status 130
// (the temporary database removed).
void run_bake_dry_run(const BakeConfig& config, const BakeCommandOptions& options, const DryRunRequest& request);

// The `cellbake bake` arguments that give another bake `plan`'s configuration
// with its floors already turned into regions (--region each, --floors none,
// --up as resolved): the config file, --set overrides (but output.database
// and cells.floors), --store, --cell-size, --near-budget and --face-size as
// given. No --out, --cells, --threads, --shard.
std::vector<std::string> bake_arguments_for_plan(const BakeCommandOptions& options, const BakePlan& plan);

// `v` in the shortest decimal text that reads back as exactly `v`.
std::string exact_number_text(double v);

}  // namespace cellbake
