#include "runner/walk/walk_path.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace cellbake {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kStepsPerSegment = 64;  // polyline resolution of each spline segment

Vec3d horizontal(const Vec3d& v, const Vec3d& up) { return v - up * dot(v, up); }

// (floor, row, column) of a cell for `up`.
std::tuple<int, int, int> plan_place(const WalkCell& c, const Vec3d& up) {
  if (std::abs(up.y) > 0.5) return {c.gy, c.gx, c.gz};
  return {c.gz, c.gy, c.gx};
}

// A polyline through the spline with the cumulative arc length at each vertex.
struct Polyline {
  std::vector<Vec3d> points;
  std::vector<double> length;  // length[0] = 0
  double total() const { return length.empty() ? 0 : length.back(); }
  Vec3d at(double s) const {
    if (points.size() == 1 || s <= 0) return points.front();
    if (s >= total()) {  // past the end: on along the last segment
      const Vec3d a = points[points.size() - 2], b = points.back();
      const double seg = length.back() - length[length.size() - 2];
      return seg > 0 ? b + (b - a) * ((s - total()) / seg) : b;
    }
    const auto it = std::upper_bound(length.begin(), length.end(), s);
    const std::size_t i = std::size_t(it - length.begin());  // length[i-1] <= s < length[i]
    const double seg = length[i] - length[i - 1];
    const double t = seg > 0 ? (s - length[i - 1]) / seg : 0;
    return points[i - 1] + (points[i] - points[i - 1]) * t;
  }
};

Polyline spline_polyline(const std::vector<Vec3d>& control) {
  Polyline p;
  const int segments = int(control.size()) - 1;
  for (int i = 0; i < segments; ++i)
    for (int k = 0; k < kStepsPerSegment; ++k) p.points.push_back(catmull_rom_point(control, i + double(k) / kStepsPerSegment));
  p.points.push_back(control.back());
  p.length.assign(p.points.size(), 0);
  for (std::size_t i = 1; i < p.points.size(); ++i) p.length[i] = p.length[i - 1] + length(p.points[i] - p.points[i - 1]);
  return p;
}

}  // namespace

std::vector<WalkCell> serpentine_order(std::vector<WalkCell> cells, const Vec3d& up) {
  std::sort(cells.begin(), cells.end(), [&](const WalkCell& a, const WalkCell& b) {
    return std::make_tuple(plan_place(a, up), a.id) < std::make_tuple(plan_place(b, up), b.id);
  });
  // Reverse every other row of each floor (counting the rows present, so gaps do not break the alternation).
  std::size_t start = 0;
  int row_rank = 0, floor = 0;
  for (std::size_t i = 1; i <= cells.size(); ++i) {
    const bool end = i == cells.size() || std::get<0>(plan_place(cells[i], up)) != std::get<0>(plan_place(cells[start], up)) ||
                     std::get<1>(plan_place(cells[i], up)) != std::get<1>(plan_place(cells[start], up));
    if (!end) continue;
    const int this_floor = std::get<0>(plan_place(cells[start], up));
    if (start == 0 || this_floor != floor) row_rank = 0, floor = this_floor;
    if (row_rank % 2 == 1) std::reverse(cells.begin() + std::ptrdiff_t(start), cells.begin() + std::ptrdiff_t(i));
    ++row_rank;
    start = i;
  }
  return cells;
}

Vec3d catmull_rom_point(const std::vector<Vec3d>& points, double u) {
  const int n = int(points.size());
  if (n < 2) throw std::invalid_argument("catmull_rom_point: needs at least 2 points");
  u = std::clamp(u, 0.0, double(n - 1));
  const int i = std::min(int(u), n - 2);
  const double f = u - i;
  const Vec3d p1 = points[std::size_t(i)], p2 = points[std::size_t(i + 1)];
  const Vec3d p0 = i > 0 ? points[std::size_t(i - 1)] : p1 * 2.0 - p2;
  const Vec3d p3 = i + 2 < n ? points[std::size_t(i + 2)] : p2 * 2.0 - p1;
  // Centripetal knots (alpha = 1/2), Barry-Goldman pyramid.
  const auto knot = [](const Vec3d& a, const Vec3d& b) { return std::max(std::sqrt(length(b - a)), 1e-9); };
  const double t0 = 0, t1 = t0 + knot(p0, p1), t2 = t1 + knot(p1, p2), t3 = t2 + knot(p2, p3);
  const double t = t1 + f * (t2 - t1);
  const Vec3d a1 = p0 * ((t1 - t) / (t1 - t0)) + p1 * ((t - t0) / (t1 - t0));
  const Vec3d a2 = p1 * ((t2 - t) / (t2 - t1)) + p2 * ((t - t1) / (t2 - t1));
  const Vec3d a3 = p2 * ((t3 - t) / (t3 - t2)) + p3 * ((t - t2) / (t3 - t2));
  const Vec3d b1 = a1 * ((t2 - t) / (t2 - t0)) + a2 * ((t - t0) / (t2 - t0));
  const Vec3d b2 = a2 * ((t3 - t) / (t3 - t1)) + a3 * ((t - t1) / (t3 - t1));
  return b1 * ((t2 - t) / (t2 - t1)) + b2 * ((t - t1) / (t2 - t1));
}

std::vector<PathView> auto_walk_path(const std::vector<WalkCell>& cells, const Vec3d& up,
                                     const AutoWalkParams& params) {
  if (cells.empty()) throw std::invalid_argument("walk: no cell to walk through");
  if (!(params.speed > 0) || !(params.fps > 0) || !(params.look_ahead > 0) || !(params.seconds >= 0))
    throw std::invalid_argument("walk: speed, fps and look-ahead must be positive, seconds not negative");
  std::vector<Vec3d> control;
  for (const WalkCell& c : serpentine_order(cells, up)) {
    const Vec3d p = (c.navigable.empty() ? c.bounds : c.navigable).center();
    if (control.empty() || length(p - control.back()) > 1e-9) control.push_back(p);
  }
  if (control.size() == 1) {  // a loop around the one centre
    const Box3d& b = cells.front().bounds;
    const Vec3d e = horizontal(b.extent(), up);
    const double side = std::abs(up.y) > 0.5 ? std::min(e.x, e.z) : std::min(e.x, e.y);
    const double r = std::max(0.25 * side, 1e-3);
    const Vec3d a = std::abs(up.y) > 0.5 ? Vec3d{0, 0, 1} : Vec3d{0, 1, 0}, x{1, 0, 0};
    const Vec3d centre = control.front();
    control.clear();
    for (int k = 0; k <= 16; ++k) {
      const double phi = 2 * kPi * k / 16;
      control.push_back(centre + x * (r * std::cos(phi)) + a * (r * std::sin(phi)));
    }
  }
  const Polyline line = spline_polyline(control);
  double duration = line.total() / params.speed;
  if (params.seconds > 0) duration = std::min(duration, params.seconds);
  const int frames = int(std::floor(duration * params.fps + 1e-9)) + 1;
  std::vector<PathView> views;
  views.reserve(std::size_t(frames));
  Vec3d heading = horizontal(control[1] - control[0], up);
  for (int k = 0; k < frames; ++k) {
    const double s = std::min(params.speed * k / params.fps, line.total());
    const Vec3d eye = line.at(s);
    Vec3d dir{0, 0, 0};
    for (const double f : {0.5, 1.0, 1.5}) {
      // Past the end the path goes on straight, so the last frames keep their heading.
      const Vec3d d = horizontal(line.at(s + f * params.look_ahead) - eye, up);
      const double l = length(d);
      if (l > 1e-9) dir = dir + d * (1.0 / l);
    }
    if (length(dir) > 1e-9) heading = dir;
    const double hl = length(heading);
    const Vec3d look_dir = hl > 1e-12 ? heading * (1.0 / hl) : (std::abs(up.y) > 0.5 ? Vec3d{0, 0, 1} : Vec3d{0, 1, 0});
    views.push_back({eye, eye + look_dir * params.look_ahead});
  }
  return views;
}

}  // namespace cellbake
