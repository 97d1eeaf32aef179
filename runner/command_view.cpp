// `cellbake view DB [options]`: the interactive viewer. It needs a window
// OpenGL context (GLFW + libGL) while this executable links OSMesa, so it is a
// separate program, `cellbake-view`, built next to this one and installed
// into libexec/cellbake/; this command replaces the process with it, passing
// every argument through.
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "runner/commands.h"

namespace cellbake {
namespace {

// cellbake-view beside this executable (the build tree), else in the install
// layout's libexec folder relative to it (bin/../libexec/cellbake).
std::filesystem::path find_view_program() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot locate this executable through /proc/self/exe: " + ec.message());
  const std::filesystem::path candidates[] = {
      self.parent_path() / "cellbake-view",
      (self.parent_path() / CELLBAKE_VIEW_DIR_FROM_BIN / "cellbake-view").lexically_normal()};
  for (const auto& candidate : candidates)
    if (std::filesystem::exists(candidate)) return candidate;
  throw std::runtime_error("cellbake-view not found (looked for " + candidates[0].string() + " and " +
                           candidates[1].string() +
                           "); it is built only when libglfw3-dev and libimgui-dev are installed "
                           "(scripts/install-deps.sh), and `cmake --install` puts it in the second place");
}

}  // namespace

void add_view_command(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("view", "Interactive viewer (runs cellbake-view; see `cellbake view --help-viewer`)");
  cmd->prefix_command();  // everything after `view` goes to cellbake-view untouched
  cmd->callback([cmd] {
    const std::filesystem::path program = find_view_program();
    std::vector<std::string> args = cmd->remaining();
    for (auto& a : args)
      if (a == "--help-viewer") a = "--help";
    std::vector<char*> argv;
    std::string name = program.string();
    argv.push_back(name.data());
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(program.c_str(), argv.data());
    throw std::runtime_error("cannot run " + program.string() + ": " + std::strerror(errno));
  });
}

}  // namespace cellbake
