// Command-line options shared by `bake` and `submit`: a config file, `--set`
// overrides, quick-bake options that need no file, and run options.
#pragma once

#include <string>
#include <vector>

#include "pipeline/bake_config.h"
#include "runner/bake_runner.h"

namespace CLI {
class App;
}

namespace cellbake {

struct BakeCommandOptions {
  std::string config_file;
  std::vector<std::string> sets;
  std::string store, up, out, shard;
  std::vector<std::string> regions;  // "X0,Y0,Z0,X1,Y1,Z1" each
  std::string floors;                // "all" or "0,2": floors as regions (pipeline/floor_regions.h)
  double cell_size = 0;
  long long near_budget = -1;
  int face_size = 0;
  bool json = false;  // the summary as JSON
  BakeOptions run;
};

// Registers the options on `cmd`.
void add_bake_options(CLI::App& cmd, BakeCommandOptions& opt);

// Builds the config: file (if any), then quick-bake options, then --set
// overrides, then validation. Throws with a message naming the bad option.
BakeConfig bake_config_from_options(BakeCommandOptions& opt);

// Prints the one-line bake summary, or (json) one JSON object: database,
// cells_selected, cells_up_to_date, cells_baked, cells_failed, cull_reused, seconds.
void print_bake_summary(const BakeSummary& s, const BakeConfig& config, bool json = false);

}  // namespace cellbake
