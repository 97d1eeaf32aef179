// Ctrl-C during a long command: a clear message and exit status 130 instead of
// a silent death. Used by `bake`, whose cells are committed one transaction
// each (WAL), so stopping at any instant loses at most the cells in flight and
// a rerun resumes (docs/reliability.md: the same guarantee as kill -9).
#pragma once

#include <sys/types.h>

namespace cellbake {

// Installs a SIGINT handler (replacing any disposition, an inherited "ignore"
// included) that writes "\n" + `message` + "\n" to stderr and ends the process
// at once with status 130 (128 + SIGINT), async-signal-safely (write, _exit).
// `message` must outlive the process (a string literal).
void exit_on_interrupt(const char* message);

// While a child process works for the command (`bake --dry-run --measure`
// bakes its cells in one): SIGINT no longer ends this process at once but is
// remembered and the child is ended (SIGTERM: quietly, without the bake's own
// "rerun to resume"; the child runs in a process group of its own, so a
// terminal's Ctrl-C reaches this process alone), so the command can clean up
// (its temporary folder) once the child has stopped. The disposition SIGINT
// had before is restored on destruction. One at a time.
class InterruptRelay {
 public:
  InterruptRelay();
  ~InterruptRelay();
  InterruptRelay(const InterruptRelay&) = delete;
  InterruptRelay& operator=(const InterruptRelay&) = delete;
  // Ends `child` on SIGINT from now on (at once when one came already).
  void relay_to(pid_t child);
  // Whether SIGINT came since construction.
  bool interrupted() const;
};

}  // namespace cellbake
