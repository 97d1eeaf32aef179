// Subcommand registration for the `cellbake` executable: each add_* function
// registers one subcommand (options, --help text and the callback that runs it).
// Callbacks throw on failure; main() turns that into a message and exit code 1.
#pragma once

namespace CLI {
class App;
}

namespace cellbake {

void add_generate_command(CLI::App& app);
void add_ingest_command(CLI::App& app);
void add_bake_command(CLI::App& app);
void add_status_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_demo_command(CLI::App& app);
void add_submit_command(CLI::App& app);
void add_merge_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_view_command(CLI::App& app);
void add_verify_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_walk_command(CLI::App& app);

}  // namespace cellbake
