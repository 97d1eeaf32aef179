#include "viewer/prefetch_order.h"

#include <algorithm>
#include <limits>
#include <tuple>

namespace cellbake {

EyeMotion::EyeMotion(std::size_t frames) : frames_(std::max<std::size_t>(frames, 2)) {}

void EyeMotion::add(const Vec3d& eye) {
  positions_.push_back(eye);
  while (positions_.size() > frames_) positions_.pop_front();
}

Vec3d EyeMotion::velocity() const {
  if (positions_.size() < 2) return {};
  return (positions_.back() - positions_.front()) * (1.0 / static_cast<double>(positions_.size() - 1));
}

double ray_entry(const Vec3d& origin, const Vec3d& direction, const Box3d& box) {
  double enter = 0, leave = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    const double o = origin[axis], d = direction[axis], lo = box.lo[axis], hi = box.hi[axis];
    if (d == 0) {
      if (o < lo || o > hi) return -1;
      continue;
    }
    double t0 = (lo - o) / d, t1 = (hi - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
    if (enter > leave) return -1;
  }
  // Touching the box only at the origin, moving away from it: not entered.
  return leave > 0 ? enter : -1;
}

PrefetchOrder prefetch_order(const CellIndex& index, const CellEntry& current, const Vec3d& eye,
                             const Vec3d& velocity, double reach) {
  const bool moving = length(velocity) > 0;
  // (not entered, entry time or distance, id): the walk's cells sort first.
  std::vector<std::tuple<bool, double, std::int64_t>> ranked;
  const Vec3d centre = current.bounds.center();
  for (const CellEntry& c : index.cells()) {
    if (c.id == current.id || !c.done || distance_to_box(centre, c.bounds) > reach) continue;
    const double entry = moving ? ray_entry(eye, velocity, c.bounds) : -1;
    if (entry >= 0) ranked.emplace_back(false, entry, c.id);
    else ranked.emplace_back(true, distance_to_box(eye, c.bounds), c.id);
  }
  std::sort(ranked.begin(), ranked.end());
  PrefetchOrder order;
  for (const auto& [rest, key, id] : ranked) order.ids.push_back(id);
  if (!ranked.empty() && !std::get<0>(ranked.front())) order.heading = std::get<2>(ranked.front());
  return order;
}

}  // namespace cellbake
