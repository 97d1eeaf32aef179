// The per-cell job's stage timer: the seconds a stage of one cell takes, in
// CellWork::seconds (the row's stage_seconds), its own time only.
#pragma once

#include <chrono>
#include <utility>

#include "pipeline/cell_job.h"

namespace cellbake {

// Adds the seconds from its construction to its destruction to the cell's
// `stage`, less those spent in pause_during: a stage's own time, without the
// stages it runs inside it (which time themselves).
class StageTimer {
 public:
  StageTimer(CellWork& work, const char* stage) : work_(work), stage_(stage), start_(Clock::now()) {}
  ~StageTimer() { stop(); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

  // Runs `nested` (a stage that times itself) with this timer stopped, and
  // returns what it returns.
  template <typename Nested>
  decltype(auto) pause_during(Nested&& nested) {
    stop();
    const Restart restart{*this};
    return std::forward<Nested>(nested)();
  }

 private:
  using Clock = std::chrono::steady_clock;
  struct Restart {
    StageTimer& timer;
    ~Restart() { timer.start_ = Clock::now(), timer.running_ = true; }
  };
  void stop() {
    if (running_) work_.seconds[stage_] += std::chrono::duration<double>(Clock::now() - start_).count();
    running_ = false;
  }

  CellWork& work_;
  const char* stage_;
  Clock::time_point start_;
  bool running_ = true;
};

}  // namespace cellbake
