#include "runner/progress.h"

#include <unistd.h>

#include <cstdio>

namespace cellbake {

ProgressBar::ProgressBar(std::string label, std::uint64_t total, std::string unit, double interval_s)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(total),
      tty_(::isatty(STDERR_FILENO) != 0),
      interval_s_(tty_ ? 0.2 : interval_s),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

void ProgressBar::update(std::uint64_t done, const std::string& note) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = done;
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_draw_).count() < interval_s_) return;
  last_draw_ = now;
  draw(false, note);
}

void ProgressBar::finish(const std::string& note) {
  std::lock_guard<std::mutex> lock(mutex_);
  draw(true, note);
}

void ProgressBar::line(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::fprintf(stderr, "%s%s\n", tty_ ? "\r\033[K" : "", text.c_str());
  if (tty_ && drawn_) draw(false, "");
  std::fflush(stderr);
}

void ProgressBar::draw(bool final, const std::string& note) {
  drawn_ = !final;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? done_ / elapsed : 0;
  char eta[32] = "";
  if (total_ > 0 && rate > 0 && !final) {
    const double left = (total_ - std::min(done_, total_)) / rate;
    std::snprintf(eta, sizeof eta, " ETA %dm%02ds", int(left) / 60, int(left) % 60);
  }
  std::string counts = std::to_string(done_) + (total_ > 0 ? "/" + std::to_string(total_) : "") + " " + unit_;
  std::string bar;
  if (tty_ && total_ > 0) {
    const int width = 30;
    const int filled = int(width * double(std::min(done_, total_)) / double(total_));
    bar = "[" + std::string(filled, '#') + std::string(width - filled, '.') + "] ";
  }
  std::fprintf(stderr, "%s%s: %s%s (%.1f %s/s, %.1fs)%s%s%s%s", tty_ ? "\r\033[K" : "", label_.c_str(), bar.c_str(),
               counts.c_str(), rate, unit_.c_str(), elapsed, eta, note.empty() ? "" : " ", note.c_str(),
               (tty_ && !final) ? "" : "\n");
  std::fflush(stderr);
}

}  // namespace cellbake
