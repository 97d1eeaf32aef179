// The `cellbake` executable: subcommands for every job (see --help).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "runner/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"cellbake: bake huge 3D models into a view-cell database (near field + textured depth meshes)"};
  app.set_version_flag("--version", std::string("cellbake ") + CELLBAKE_VERSION);
  app.require_subcommand(1);
  cellbake::add_generate_command(app);
  cellbake::add_ingest_command(app);
  cellbake::add_bake_command(app);
  cellbake::add_status_command(app);
  cellbake::add_demo_command(app);
  cellbake::add_submit_command(app);
  cellbake::add_merge_command(app);
  cellbake::add_render_command(app);
  cellbake::add_view_command(app);
  cellbake::add_verify_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    const std::string cmd = app.get_subcommands().empty() ? "cellbake" : "cellbake " + app.get_subcommands()[0]->get_name();
    std::fprintf(stderr, "%s: error: %s\n", cmd.c_str(), e.what());
    return 1;
  }
  return 0;
}
