// Files a command writes besides its own database (rendered images, CSV,
// verify reports, Slurm scripts, generated PLY models): never over an SQLite
// database or a file the command reads, never through a symbolic link or onto
// a directory, device or pipe, and either complete or not there at all.
#pragma once

#include <filesystem>
#include <string_view>
#include <vector>

namespace cellbake {

// The files a command reads: none of them may be an output.
using InputFiles = std::vector<std::filesystem::path>;

// Throws std::runtime_error naming `path` when something is there that a new
// file must never replace by a rename: a symbolic link (name its target
// instead), or anything but a regular file (a directory, a device such as
// /dev/full, a pipe, a socket). `new_file` names what would replace it ("a
// geometry store", "an output"). Nothing there, or a regular file, passes.
void refuse_non_regular_target(const std::filesystem::path& path, std::string_view new_file);

// Throws std::runtime_error naming `target` and why when an output must not be
// written there: it is the same file (device and inode, following symbolic
// and hard links) as one of `inputs`; it begins with SQLite's header (a
// database, whatever its name) or is an SQLite write-ahead log or rollback
// journal; it cannot be read to tell; or refuse_non_regular_target refuses it.
void check_output_target(const std::filesystem::path& target, const InputFiles& inputs);

// An output written to a temporary file in its folder (TARGET.tmp-PID-N,
// permissions 0666 less the umask) and renamed over the target only by
// commit(): readers never see half a file, and a failed write leaves the
// target as it was. Every write, the fsync and the close are checked.
class OutputFile {
 public:
  // Checks `target` (check_output_target) and creates the temporary; throws
  // std::runtime_error naming the file with the system's reason.
  OutputFile(const std::filesystem::path& target, const InputFiles& inputs);
  // Removes the temporary unless committed.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Appends `bytes`; throws std::runtime_error "TARGET: cannot write: REASON".
  void write(std::string_view bytes);
  // Flushes to disk, closes, checks the target again and renames the
  // temporary over it. Throws std::runtime_error naming the target (the
  // temporary is removed, the target untouched).
  void commit();
  const std::filesystem::path& target() const { return target_; }

 private:
  [[noreturn]] void fail(const char* what, int error);

  std::filesystem::path target_, temp_;
  InputFiles inputs_;
  int fd_ = -1;
  bool committed_ = false;
};

// Writes `bytes` as `target` through an OutputFile.
void write_output_file(const std::filesystem::path& target, std::string_view bytes, const InputFiles& inputs);

}  // namespace cellbake
