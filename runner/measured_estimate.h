// `bake --dry-run --measure K`'s measurement: the chosen cells baked for real,
// with the bake's own settings, into a temporary database under $TMPDIR that
// is removed afterwards — also when the bake fails or Ctrl-C stops it. The
// cells are baked by a child process (this executable: `cellbake bake ARGS
// --cells IDS --out TMP/cells.db`), so the CPU time and peak memory measured
// are the bake's alone (wait4's rusage), setup included: opening the store,
// building the ray caster's BVHs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cellbake {

struct CellMeasurement {
  std::vector<std::int64_t> ids;     // the cells asked for
  std::uint64_t cells_done = 0;      // rows the bake wrote as done
  int threads = 0;
  double cpu_seconds = 0;            // the child's user + system time
  double wall_seconds = 0;
  double in_thread_seconds = 0;      // the cells' stage seconds (rows' stage_seconds), summed
  double bytes = 0;                  // stored for those cells (CellDb totals)
  std::uint64_t peak_rss_bytes = 0;  // the child's maximum resident set
  bool interrupted = false;          // SIGINT came: the child ended, nothing measured, the temporary folder removed
};

// Bakes `ids` (not empty) with `bake_args` (the `cellbake bake` options that
// give the configuration: config file, --set, --store, --region, ...; no
// --out, --cells, --threads or --dry-run) on `threads` threads (>= 1). `quiet`
// hides the child's progress. Returns with `interrupted` set when SIGINT
// came (the child is ended: runner/interrupt.h InterruptRelay); throws std::runtime_error naming the
// cells when the bake fails or did not write them all. The temporary folder
// is gone whenever this returns or throws.
CellMeasurement measure_cells(const std::vector<std::string>& bake_args, const std::vector<std::int64_t>& ids,
                              int threads, bool quiet);

// "1,5,9-12": `ids` (ascending) as a --cells selection.
std::string cell_selection_text(const std::vector<std::int64_t>& ids);

}  // namespace cellbake
