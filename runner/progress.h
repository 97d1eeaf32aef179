// Progress reporting for long work: a redrawn bar with rate and ETA on a TTY,
// plain periodic lines (at most one per `interval_s`) otherwise. Thread-safe.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace cellbake {

class ProgressBar {
 public:
  // `total` = 0 means unknown (no ETA). `unit` names what is counted ("cells").
  ProgressBar(std::string label, std::uint64_t total, std::string unit, double interval_s = 5.0);
  // Sets the number done so far and redraws when due.
  void update(std::uint64_t done, const std::string& note = "");
  // Prints the final line.
  void finish(const std::string& note = "");
  // Prints `text` as a line of its own (stderr) without breaking the bar: on a
  // TTY the bar is cleared first and redrawn after it.
  void line(const std::string& text);

 private:
  void draw(bool final, const std::string& note);
  std::string label_, unit_;
  std::uint64_t total_, done_ = 0;
  bool tty_;
  bool drawn_ = false;  // a bar is on the TTY's current line
  double interval_s_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

}  // namespace cellbake
