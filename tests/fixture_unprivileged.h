// Running cellbake as a user without privileges, so that file permissions
// (a read-only folder) really apply: tests run as root in CI, and root ignores
// them. As root the command runs as `nobody` through setpriv (util-linux);
// as anyone else it runs as that user.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include "tests/test_support.h"

namespace cellbake::test {

// Sets `prefix` to what runs a command without privileges ("" for a normal
// user, setpriv to nobody for root); false when root has no setpriv.
inline bool unprivileged_prefix(std::string& prefix) {
  if (::geteuid() != 0) {
    prefix.clear();
    return true;
  }
  if (run_shell("setpriv --reuid=65534 --regid=65534 --clear-groups true").exit_code != 0) return false;
  prefix = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  return true;
}

// Runs the built cellbake with `args` without privileges (see above).
inline CommandResult run_cellbake_unprivileged(const std::string& prefix, const std::string& args) {
  return run_shell(prefix + std::string(CELLBAKE_BINARY) + " " + args);
}

// A folder nobody may write to: read-only for every user.
inline void make_read_only_folder(const std::filesystem::path& folder) {
  std::filesystem::permissions(folder,
                               std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec |
                                   std::filesystem::perms::group_read | std::filesystem::perms::group_exec |
                                   std::filesystem::perms::others_read | std::filesystem::perms::others_exec);
}

// A folder everyone may write to (outputs of an unprivileged command).
inline void make_writable_folder(const std::filesystem::path& folder) {
  std::filesystem::create_directories(folder);
  std::filesystem::permissions(folder, std::filesystem::perms::all);
}

}  // namespace cellbake::test
