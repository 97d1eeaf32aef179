// How much the `cellbake` commands print, set once by the global options
// -q/--quiet and -v/--verbose before a command runs:
//  * quiet: errors, warnings and each command's final summary; no progress
//    lines or notes;
//  * normal: also progress (a bar on a TTY, periodic lines otherwise) and notes;
//  * verbose: also per-item detail where it is cheap (bake: each cell's stage
//    timings as it is written; ingest: each source file; verify: each cell).
// Commands read it when they start and pass plain flags down (BakeOptions,
// VerifyOptions), so the runners themselves hold no global state.
#pragma once

namespace cellbake {

enum class Verbosity { quiet, normal, verbose };

void set_verbosity(Verbosity v);
Verbosity verbosity();
inline bool quiet_output() { return verbosity() == Verbosity::quiet; }
inline bool verbose_output() { return verbosity() == Verbosity::verbose; }

}  // namespace cellbake
