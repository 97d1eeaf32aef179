// Ctrl-C during a long command: a clear message and exit status 130 instead of
// a silent death. Used by `bake`, whose cells are committed one transaction
// each (WAL), so stopping at any instant loses at most the cells in flight and
// a rerun resumes (docs/reliability.md: the same guarantee as kill -9).
#pragma once

namespace cellbake {

// Installs a SIGINT handler (replacing any disposition, an inherited "ignore"
// included) that writes "\n" + `message` + "\n" to stderr and ends the process
// at once with status 130 (128 + SIGINT), async-signal-safely (write, _exit).
// `message` must outlive the process (a string literal).
void exit_on_interrupt(const char* message);

}  // namespace cellbake
