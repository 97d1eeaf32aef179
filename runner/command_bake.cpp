// `cellbake bake [CONFIG.toml] [--set k=v]... [quick-bake options] [--threads N] [--cells SEL] [--force]`
#include <CLI/CLI.hpp>

#include <cstdio>
#include <thread>

#include <nlohmann/json.hpp>

#include "pipeline/bake_config.h"
#include "pipeline/bake_estimate.h"
#include "runner/bake_command_options.h"
#include "runner/bake_runner.h"
#include "runner/commands.h"
#include "runner/console.h"
#include "runner/interrupt.h"
#include "storage/geometry_store.h"
#include "storage/store_check.h"

namespace cellbake {

void print_bake_summary(const BakeSummary& s, const BakeConfig& config, bool json) {
  if (json) {
    const nlohmann::json j{{"database", config.database.string()},
                           {"cells_selected", s.cells_selected},
                           {"cells_up_to_date", s.cells_up_to_date},
                           {"cells_baked", s.cells_baked},
                           {"cells_failed", s.cells_failed},
                           {"cull_reused", s.cull_reused},
                           {"seconds", s.seconds},
                           {"sample_backend", s.sample_backend},
                           {"sample_device", s.sample_device}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("bake %s: %llu cells selected, %llu up to date, %llu baked, %llu failed (cull box reused for %llu) in "
              "%.1f s",
              config.database.c_str(), (unsigned long long)s.cells_selected, (unsigned long long)s.cells_up_to_date,
              (unsigned long long)s.cells_baked, (unsigned long long)s.cells_failed, (unsigned long long)s.cull_reused,
              s.seconds);
  if (!s.sample_backend.empty())  // on the same line: --quiet prints the summary line alone
    std::printf("; samples rendered by %s on %s", s.sample_backend.c_str(), s.sample_device.c_str());
  std::printf("\n");
}

namespace {

// `bake --dry-run`: what the bake would do (plan_bake), and nothing written.
void print_dry_run(const BakeConfig& given, const BakeOptions& options, bool json) {
  validate_bake_config(given);
  require_sound_store(given.store, options.check_store);
  const GeometryStore store(given.store);
  const BakePlan plan = plan_bake(given, options, store);
  const BakeConfig& c = plan.config;
  const int threads = options.threads > 0 ? options.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  const BakeEstimate e = estimate_bake(plan.cells.size(), c.face_size, threads, plan.model_triangles);
  const bool no_far_field = plan.model_triangles <= c.near_budget;
  if (json) {
    nlohmann::json j{{"dry_run", true},
                     {"database", c.database.string()},
                     {"database_exists", std::filesystem::exists(c.database)},
                     {"store", c.store.string()},
                     {"model_triangles", plan.model_triangles},
                     {"up", c.up},
                     {"cell_size", c.cell_size},
                     {"cells_total", plan.cells_total},
                     {"cells_selected", plan.cells.size()},
                     {"near_budget", c.near_budget},
                     {"face_size", c.face_size},
                     {"threads", threads},
                     {"estimated_seconds", e.seconds},
                     {"estimated_core_seconds_per_cell", e.core_seconds_per_cell},
                     {"estimated_bytes_per_cell", e.bytes_per_cell},
                     {"estimated_bytes", e.bytes},
                     {"no_far_field", no_far_field}};
    nlohmann::json ids = nlohmann::json::array();
    for (const CellSpec& cell : plan.cells) ids.push_back(cell.id);
    j["cell_ids"] = ids;
    if (!plan.up_note.empty()) j["up_note"] = plan.up_note;
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (!plan.up_note.empty()) std::fprintf(stderr, "%s\n", plan.up_note.c_str());
  std::printf("dry run: nothing written (%s %s)\n", c.database.c_str(),
              std::filesystem::exists(c.database) ? "exists; a bake resumes it" : "would be created");
  std::printf("store: %s, %llu triangles, up %s\n", c.store.c_str(), (unsigned long long)plan.model_triangles,
              c.up.c_str());
  std::printf("cells: %zu selected of %llu (cell size %g)", plan.cells.size(), (unsigned long long)plan.cells_total,
              c.cell_size);
  if (!plan.cells.empty())
    std::printf(", ids %lld..%lld", (long long)plan.cells.front().id, (long long)plan.cells.back().id);
  std::printf("\nnear budget: %llu triangles per cell%s\n", (unsigned long long)c.near_budget,
              no_far_field ? " (the whole model fits: no far field; lower it with --near-budget)" : "");
  std::printf(
      "estimate: ~%s on %d threads (%.1f core-seconds per cell at %d² faces), ~%.0f KB per cell, ~%.1f MB "
      "in all (the demo plant's figures scaled to this model's size; a guide, not a promise)\n",
      duration_text(e.seconds).c_str(), threads, e.core_seconds_per_cell, c.face_size, e.bytes_per_cell / 1e3,
      e.bytes / 1e6);
}

}  // namespace

void add_bake_command(CLI::App& app) {
  auto opt = std::make_shared<BakeCommandOptions>();
  CLI::App* cmd = app.add_subcommand("bake", "Bake view cells (near field + textured depth meshes) into a cell database");
  add_bake_options(*cmd, *opt);
  auto dry_run = std::make_shared<bool>(false);
  cmd->add_flag("--dry-run", *dry_run,
                "Check the config and selection, print the cells, near budget, estimated time and bytes; write nothing");
  cmd->callback([opt, dry_run] {
    const BakeConfig config = bake_config_from_options(*opt);
    if (*dry_run) return print_dry_run(config, opt->run, opt->json);
    exit_on_interrupt("interrupted — rerun the same command to resume");
    opt->run.quiet = quiet_output();
    opt->run.verbose = verbose_output();
    const BakeSummary s = run_bake(config, opt->run);
    print_bake_summary(s, config, opt->json);
    if (s.cells_failed > 0) throw std::runtime_error(std::to_string(s.cells_failed) + " cell(s) failed; see messages above");
  });
}

}  // namespace cellbake
