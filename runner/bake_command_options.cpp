#include "runner/bake_command_options.h"

#include <cmath>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <sstream>

namespace cellbake {

void add_bake_options(CLI::App& cmd, BakeCommandOptions& opt) {
  cmd.add_option("config", opt.config_file, "Bake configuration (TOML); optional with --store/--region/--cell-size")
      ->check(CLI::ExistingFile);
  cmd.add_option("--set", opt.sets, "Override a config key: section.key=value (repeatable)");
  cmd.add_option("--store", opt.store, "Geometry store (overrides [model] store)");
  cmd.add_option("--up", opt.up,
                 "Up axis: z or y (default: [model] up, else the one the geometry store recorded at ingest, else z)")
      ->check(CLI::IsMember({"z", "y"}));
  cmd.add_option("--region", opt.regions, "Box of eye positions X0,Y0,Z0,X1,Y1,Z1 (repeatable)");
  cmd.add_option("--floors", opt.floors,
                 "Bake whole floors: all, or indices like 0,2 of the floors `cellbake info` finds (0 = the lowest); "
                 "eyes [cells] eye_height above each (default 1.7 m in the units `info` takes the model in), over the "
                 "--region's x/y extent (none: each floor's walkable extent, the region `info` suggests for the main floor)");
  cmd.add_option("--cell-size", opt.cell_size, "Edge of a cubic view cell, model units")->check(CLI::PositiveNumber);
  cmd.add_option("--near-budget", opt.near_budget,
                 "Near-field triangle budget per cell (default: [near] budget, 100000, or near.budget_fraction of a "
                 "small model's triangles)")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--face-size", opt.face_size, "Stored cube-face resolution, pixels (default: [sample] face_size, 512)")
      ->check(CLI::Range(8, 4096));
  cmd.add_option("--out", opt.out, "Output cell database (overrides [output] database)");
  cmd.add_option("--threads", opt.run.threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  cmd.add_option("--cells", opt.run.cells, "Only these cell ids, e.g. 1-10,15,20-");
  cmd.add_flag("--force", opt.run.force, "Recompute cells even when their stored hash matches");
  cmd.add_flag("--check-store", opt.run.check_store,
               "Check the geometry store fully first (content hash recomputed, R-tree, every chunk decoded); "
               "by default only its row counts are compared with what ingest recorded");
  cmd.add_option("--shard", opt.shard, "Bake only shard I of N (I/N, 0-based)");
  cmd.add_flag("--json", opt.json, "Print the summary as JSON (progress still goes to stderr; -q hides it)");
}

BakeConfig bake_config_from_options(BakeCommandOptions& opt) {
  BakeConfig config = opt.config_file.empty() ? BakeConfig{} : load_bake_config(opt.config_file);
  if (!opt.store.empty()) config.store = opt.store;
  if (!opt.up.empty()) config.up = opt.up, config.up_given = true;
  if (!opt.regions.empty()) {
    config.regions.clear();
    for (const auto& text : opt.regions) {
      std::vector<double> r;
      std::stringstream ss(text);
      std::string item;
      while (std::getline(ss, item, ',')) {
        try {
          r.push_back(std::stod(item));
        } catch (const std::exception&) {
          throw std::runtime_error("--region '" + text + "': '" + item + "' is not a number");
        }
        if (!std::isfinite(r.back()))
          throw std::runtime_error("--region '" + text + "': '" + item + "' is not a finite number");
      }
      if (r.size() != 6) throw std::runtime_error("--region needs 6 numbers X0,Y0,Z0,X1,Y1,Z1");
      Box3d b{{r[0], r[1], r[2]}, {r[3], r[4], r[5]}};
      if (b.empty()) throw std::runtime_error("--region: the minimum corner must be <= the maximum corner");
      config.regions.push_back(b);
    }
  }
  if (!opt.floors.empty()) config.floors = parse_floor_selection(opt.floors, "--floors");
  if (std::isnan(opt.cell_size) || std::isinf(opt.cell_size))
    throw std::runtime_error("--cell-size must be a finite number > 0");
  if (opt.cell_size > 0) config.cell_size = opt.cell_size;
  if (opt.near_budget >= 0) config.near_budget = static_cast<std::uint64_t>(opt.near_budget);
  if (opt.face_size > 0) config.face_size = opt.face_size;
  if (!opt.out.empty()) config.database = opt.out;
  for (const auto& s : opt.sets) apply_override(config, s);
  if (!opt.shard.empty()) {
    int i = -1, n = -1;
    if (std::sscanf(opt.shard.c_str(), "%d/%d", &i, &n) != 2 || n < 1 || i < 0 || i >= n)
      throw std::runtime_error("--shard '" + opt.shard + "': expected I/N with 0 <= I < N");
    opt.run.shard_index = i;
    opt.run.shard_count = n;
  }
  validate_bake_config(config);
  return config;
}

}  // namespace cellbake
