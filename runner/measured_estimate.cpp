#include "runner/measured_estimate.h"

#include <fcntl.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "pipeline/cell_job.h"
#include "runner/interrupt.h"
#include "storage/cell_db.h"

extern char** environ;

namespace cellbake {
namespace {

// A fresh directory $TMPDIR/cellbake-measure-XXXXXX, removed with everything in it.
class MeasureFolder {
 public:
  MeasureFolder() {
    std::string name = (std::filesystem::temp_directory_path() / "cellbake-measure-XXXXXX").string();
    if (!::mkdtemp(name.data()))
      throw std::runtime_error("cannot create a temporary folder in " +
                               std::filesystem::temp_directory_path().string() + ": " + std::strerror(errno));
    path_ = name;
  }
  ~MeasureFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  MeasureFolder(const MeasureFolder&) = delete;
  MeasureFolder& operator=(const MeasureFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

double seconds_of(const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); }

}  // namespace

std::string cell_selection_text(const std::vector<std::int64_t>& ids) {
  std::string text;
  for (std::size_t i = 0; i < ids.size();) {
    std::size_t j = i;
    while (j + 1 < ids.size() && ids[j + 1] == ids[j] + 1) ++j;
    text += (text.empty() ? "" : ",") + std::to_string(ids[i]);
    if (j > i) text += "-" + std::to_string(ids[j]);
    i = j + 1;
  }
  return text;
}

CellMeasurement measure_cells(const std::vector<std::string>& bake_args, const std::vector<std::int64_t>& ids,
                              int threads, bool quiet) {
  if (ids.empty()) throw std::invalid_argument("measure_cells: no cells to measure");
  CellMeasurement m;
  m.ids = ids;
  m.threads = std::max(1, threads);
  const std::string selection = cell_selection_text(ids);
  InterruptRelay relay;  // outlives the folder: a Ctrl-C while it is removed is relayed, not fatal
  const MeasureFolder folder;
  const std::filesystem::path database = folder.path() / "cells.db";

  const std::string binary = std::filesystem::read_symlink("/proc/self/exe").string();
  std::vector<std::string> args{binary, "bake"};
  args.insert(args.end(), bake_args.begin(), bake_args.end());
  args.insert(args.end(), {"--cells", selection, "--out", database.string(), "--threads", std::to_string(m.threads)});
  if (quiet) args.push_back("--quiet");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);  // its summary line
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);  // a group of its own: Ctrl-C reaches us, we end it
  posix_spawnattr_setpgroup(&attributes, 0);
  pid_t child = 0;
  const auto start = std::chrono::steady_clock::now();
  const int spawned = posix_spawn(&child, binary.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0)
    throw std::runtime_error("cannot start the measurement bake (" + binary + "): " + std::strerror(spawned));
  relay.relay_to(child);
  int status = 0;
  rusage usage{};
  while (::wait4(child, &status, 0, &usage) < 0)
    if (errno != EINTR) throw std::runtime_error(std::string("waiting for the measurement bake: ") + std::strerror(errno));
  m.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m.cpu_seconds = seconds_of(usage.ru_utime) + seconds_of(usage.ru_stime);
  m.peak_rss_bytes = std::uint64_t(usage.ru_maxrss) * 1024;  // KiB on Linux
  if (relay.interrupted()) {
    m.interrupted = true;
    return m;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("the measurement bake of cells " + selection + " failed (" +
                             (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                                : "signal " + std::to_string(WTERMSIG(status))) +
                             "); its messages are above");
  const CellDb db(database, CellDb::Mode::read_only);
  const CellDbTotals totals = db.totals();
  m.cells_done = totals.cells_done;
  m.bytes = double(totals.bytes);
  for (const char* stage : kStageNames)  // the stages, not the timings measured inside them
    if (const auto it = totals.stage_seconds.find(stage); it != totals.stage_seconds.end()) m.in_thread_seconds += it->second;
  if (m.cells_done != ids.size())
    throw std::runtime_error("the measurement bake wrote " + std::to_string(m.cells_done) + " of the " +
                             std::to_string(ids.size()) + " cells asked for (" + selection + ")");
  return m;
}

}  // namespace cellbake
