// `cellbake view DB [options]`: the interactive viewer. It needs a window
// OpenGL context (GLFW + libGL) while this executable links OSMesa, so it is a
// separate program, `cellbake-view`, built next to this one; this command
// replaces the process with it, passing every argument through.
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

// cellbake-view next to this executable, else in the build tree's viewer/ folder.
std::filesystem::path find_view_program() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot locate this executable through /proc/self/exe: " + ec.message());
  for (const auto& candidate : {self.parent_path() / "cellbake-view", self.parent_path().parent_path() / "viewer" / "cellbake-view"})
    if (std::filesystem::exists(candidate)) return candidate;
  throw std::runtime_error("cellbake-view not found next to " + self.string() +
                           " (build it: it needs libglfw3-dev and libimgui-dev, see scripts/install-deps.sh)");
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
