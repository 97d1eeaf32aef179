// The `cellbake` executable: subcommands for every job (see --help).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include "runner/commands.h"
#include "runner/console.h"
#include "runner/heap_tuning.h"

namespace {

// "generate, ingest, ..." in registration order.
std::vector<CLI::App*> commands(CLI::App& app) {
  return app.get_subcommands(std::function<bool(CLI::App*)>([](CLI::App*) { return true; }));
}

std::string command_list(CLI::App& app) {
  std::string list;
  for (const CLI::App* sub : commands(app)) list += (list.empty() ? "" : ", ") + sub->get_name();
  return list;
}

bool is_command(CLI::App& app, const std::string& word) {
  for (CLI::App* sub : commands(app))
    if (sub->check_name(word)) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  cellbake::keep_large_blocks_in_the_heap();
  CLI::App app{"cellbake: bake huge 3D models into a view-cell database (near field + textured depth meshes)"};
  app.set_version_flag("-V,--version", std::string("cellbake ") + CELLBAKE_VERSION);
  app.require_subcommand(1);
  // Output level for every command, before or after its name (`cellbake -q bake ...` or `cellbake bake ... -q`).
  CLI::Option* quiet = app.add_flag_callback(
      "-q,--quiet", [] { cellbake::set_verbosity(cellbake::Verbosity::quiet); },
      "Print only errors, warnings and the final summary (no progress)");
  CLI::Option* verbose = app.add_flag_callback(
      "-v,--verbose", [] { cellbake::set_verbosity(cellbake::Verbosity::verbose); },
      "Print more: each cell's stage timings (bake), each cell's result (verify), every bake parameter (status)");
  quiet->excludes(verbose);
  cellbake::add_generate_command(app);
  cellbake::add_info_command(app);
  cellbake::add_ingest_command(app);
  cellbake::add_bake_command(app);
  cellbake::add_status_command(app);
  cellbake::add_demo_command(app);
  cellbake::add_submit_command(app);
  cellbake::add_merge_command(app);
  cellbake::add_render_command(app);
  cellbake::add_view_command(app);
  cellbake::add_verify_command(app);
  cellbake::add_export_command(app);
  cellbake::add_walk_command(app);
  // The global options are taken after a command's own too; `view` passes everything to cellbake-view.
  for (CLI::App* sub : commands(app))
    if (sub->get_name() != "view") sub->fallthrough();
  // Line-buffered even into a file or pipe, so summaries (stdout) and progress
  // and warnings (stderr) keep their order in a shared log (a Slurm task's).
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  // An unknown first word is a mistyped command: say so and list the commands
  // (CLI11 would answer "A subcommand is required", exit 106). Exit 2, like a usage error.
  if (argc > 1 && argv[1][0] != '-' && !is_command(app, argv[1])) {
    std::fprintf(stderr, "cellbake: unknown command '%s'\ncommands: %s\n(`cellbake --help` describes them)\n", argv[1],
                 command_list(app).c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::RequiredError& e) {
    if (app.get_subcommands().empty() && std::string(e.what()).find("subcommand") != std::string::npos) {
      std::fprintf(stderr, "cellbake: a command is needed: %s\n(`cellbake --help` describes them)\n",
                   command_list(app).c_str());
      return 2;
    }
    return app.exit(e);
  } catch (const CLI::ExcludesError& e) {
    // -q/-v: one line in our words, exit 2 like the other usage errors above.
    if (quiet->count() > 0 && verbose->count() > 0) {
      std::fprintf(stderr, "cellbake: -q/--quiet and -v/--verbose contradict each other: give one of them\n");
      return 2;
    }
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    const std::string cmd = app.get_subcommands().empty() ? "cellbake" : "cellbake " + app.get_subcommands()[0]->get_name();
    std::fprintf(stderr, "%s: error: %s\n", cmd.c_str(), e.what());
    return 1;
  }
  return 0;
}
