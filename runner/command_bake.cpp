// `cellbake bake [CONFIG.toml] [--set k=v]... [quick-bake options] [--threads N] [--cells SEL] [--force]`
#include <CLI/CLI.hpp>

#include <cstdio>
#include <thread>

#include <nlohmann/json.hpp>

#include "pipeline/bake_config.h"
#include "pipeline/bake_estimate.h"
#include "pipeline/bake_parameters.h"
#include "runner/bake_command_options.h"
#include "runner/bake_dry_run.h"
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


void add_bake_command(CLI::App& app) {
  auto opt = std::make_shared<BakeCommandOptions>();
  CLI::App* cmd = app.add_subcommand("bake", "Bake view cells (near field + textured depth meshes) into a cell database");
  add_bake_options(*cmd, *opt);
  auto dry_run = std::make_shared<bool>(false);
  auto request = std::make_shared<DryRunRequest>();
  cmd->add_flag("--dry-run", *dry_run,
                "Check the config and selection, print the cells, near budget, estimated time and bytes; write nothing");
  CLI::Option* measure =
      cmd->add_option("--measure", request->measure,
                      "With --dry-run: bake K cells chosen stratified over the selection (floors, grid) into a "
                      "temporary database (removed), measure CPU-seconds and bytes per cell, and project the whole "
                      "bake on --threads threads and on Slurm shards")
          ->check(CLI::Range(1, 100000));
  cmd->add_option("--shards", request->shards,
                  "With --dry-run --measure: the Slurm shard counts to project onto, each of --threads threads")
      ->delimiter(',')
      ->check(CLI::Range(1, 1000000))
      ->needs(measure)
      ->capture_default_str();
  auto list_parameters = std::make_shared<bool>(false);
  cmd->add_flag("--list-parameters", *list_parameters,
                "Print every config key (type, range, default, the hash it enters, meaning) as Markdown "
                "(docs/configuration.md) and exit");
  cmd->callback([opt, dry_run, request, list_parameters] {
    if (*list_parameters) {
      std::fputs(bake_parameters_markdown().c_str(), stdout);
      return;
    }
    const BakeConfig config = bake_config_from_options(*opt);
    if (request->measure > 0 && !*dry_run) throw std::runtime_error("--measure goes with --dry-run");
    request->json = opt->json;
    if (*dry_run) return run_bake_dry_run(config, *opt, *request);
    exit_on_interrupt("interrupted — rerun the same command to resume");
    opt->run.quiet = quiet_output();
    opt->run.verbose = verbose_output();
    const BakeSummary s = run_bake(config, opt->run);
    print_bake_summary(s, config, opt->json);
    if (s.cells_failed > 0) throw std::runtime_error(std::to_string(s.cells_failed) + " cell(s) failed; see messages above");
  });
}

}  // namespace cellbake
