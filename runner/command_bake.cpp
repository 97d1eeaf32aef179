// `cellbake bake [CONFIG.toml] [--set k=v]... [quick-bake options] [--threads N] [--cells SEL] [--force]`
#include <CLI/CLI.hpp>

#include <cstdio>

#include <nlohmann/json.hpp>

#include "pipeline/bake_config.h"
#include "runner/bake_command_options.h"
#include "runner/bake_runner.h"
#include "runner/commands.h"
#include "runner/console.h"
#include "runner/interrupt.h"

namespace cellbake {

void print_bake_summary(const BakeSummary& s, const BakeConfig& config, bool json) {
  if (json) {
    const nlohmann::json j{{"database", config.database.string()}, {"cells_selected", s.cells_selected},
                           {"cells_up_to_date", s.cells_up_to_date}, {"cells_baked", s.cells_baked},
                           {"cells_failed", s.cells_failed},       {"cull_reused", s.cull_reused},
                           {"seconds", s.seconds}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("bake %s: %llu cells selected, %llu up to date, %llu baked, %llu failed (cull box reused for %llu) in "
              "%.1f s\n",
              config.database.c_str(), (unsigned long long)s.cells_selected, (unsigned long long)s.cells_up_to_date,
              (unsigned long long)s.cells_baked, (unsigned long long)s.cells_failed, (unsigned long long)s.cull_reused,
              s.seconds);
}

void add_bake_command(CLI::App& app) {
  auto opt = std::make_shared<BakeCommandOptions>();
  CLI::App* cmd = app.add_subcommand("bake", "Bake view cells (near field + textured depth meshes) into a cell database");
  add_bake_options(*cmd, *opt);
  cmd->callback([opt] {
    const BakeConfig config = bake_config_from_options(*opt);
    exit_on_interrupt("interrupted — rerun the same command to resume");
    opt->run.quiet = quiet_output();
    opt->run.verbose = verbose_output();
    const BakeSummary s = run_bake(config, opt->run);
    print_bake_summary(s, config, opt->json);
    if (s.cells_failed > 0) throw std::runtime_error(std::to_string(s.cells_failed) + " cell(s) failed; see messages above");
  });
}

}  // namespace cellbake
