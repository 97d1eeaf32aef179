#include "viewer/frame_time_budget.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace cellbake {

FrameTimeBudget::FrameTimeBudget(double target_ms, std::size_t window)
    : target_ms_(target_ms), window_(std::max<std::size_t>(window, 1)) {
  if (!(target_ms > 0) || !std::isfinite(target_ms))
    throw std::invalid_argument("frame time budget: the target must be a positive number of milliseconds");
}

void FrameTimeBudget::add(double frame_ms, std::uint64_t triangles) {
  if (triangles == 0 || !(frame_ms > 0) || !std::isfinite(frame_ms)) return;
  ms_per_triangle_.push_back(frame_ms / double(triangles));
  if (ms_per_triangle_.size() > window_) ms_per_triangle_.pop_front();
}

std::uint64_t FrameTimeBudget::triangles() const {
  if (ms_per_triangle_.empty()) return 0;
  std::vector<double> v(ms_per_triangle_.begin(), ms_per_triangle_.end());
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  const double median = v[v.size() / 2];
  return std::max<std::uint64_t>(1, std::uint64_t(std::min(1e15, target_ms_ / median)));
}

std::uint64_t chunk_allowance(std::uint64_t frame_triangles, std::uint64_t other_triangles) {
  if (frame_triangles == 0) return 0;
  return frame_triangles > other_triangles ? frame_triangles - other_triangles : 1;
}

}  // namespace cellbake
