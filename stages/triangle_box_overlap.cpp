// Triangle / box separating-axis test and the Chebyshev point-triangle distance.
// Reference: T. Akenine-Möller, "Fast 3D Triangle-Box Overlap Testing",
// Journal of Graphics Tools 6(1):29-33, 2001.
#include "stages/triangle_box_overlap.h"

#include <algorithm>
#include <cmath>

namespace cellbake {
namespace {

struct Interval {
  double lo, hi;
};

Interval project3(double p0, double p1, double p2) {
  return {std::min(std::min(p0, p1), p2), std::max(std::max(p0, p1), p2)};
}

// Projections of the three relative corners on axis (nx, ny, nz).
Interval project(const Vec3d& v0, const Vec3d& v1, const Vec3d& v2, const Vec3d& n) {
  return project3(dot(v0, n), dot(v1, n), dot(v2, n));
}

// True when the projected interval misses [-r, r].
bool separated(Interval p, double r) { return p.lo > r || p.hi < -r; }

// The 13 candidate separating axes for a triangle with relative corners
// v0..v2. Calls visit(interval, n_abs) for each, where n_abs is the absolute
// axis (for the box radius) — the 3 face normals, the triangle normal and the
// 9 cross products of the triangle edges with the box axes.
template <typename Visit>
bool for_each_axis(const Vec3d& v0, const Vec3d& v1, const Vec3d& v2, Visit&& visit) {
  // Box face normals.
  if (!visit(project3(v0.x, v1.x, v2.x), Vec3d{1, 0, 0})) return false;
  if (!visit(project3(v0.y, v1.y, v2.y), Vec3d{0, 1, 0})) return false;
  if (!visit(project3(v0.z, v1.z, v2.z), Vec3d{0, 0, 1})) return false;
  const Vec3d e[3] = {v1 - v0, v2 - v1, v0 - v2};
  // Triangle normal.
  const Vec3d n = cross(e[0], e[1]);
  if (!visit(project(v0, v1, v2, n), Vec3d{std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)})) return false;
  // Edge x box axis: x -> (0, e.z, -e.y), y -> (-e.z, 0, e.x), z -> (e.y, -e.x, 0).
  for (const Vec3d& d : e) {
    const Vec3d a{std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)};
    if (!visit(project3(v0.y * d.z - v0.z * d.y, v1.y * d.z - v1.z * d.y, v2.y * d.z - v2.z * d.y),
               Vec3d{0, a.z, a.y}))
      return false;
    if (!visit(project3(v0.z * d.x - v0.x * d.z, v1.z * d.x - v1.x * d.z, v2.z * d.x - v2.x * d.z),
               Vec3d{a.z, 0, a.x}))
      return false;
    if (!visit(project3(v0.x * d.y - v0.y * d.x, v1.x * d.y - v1.y * d.x, v2.x * d.y - v2.y * d.x),
               Vec3d{a.y, a.x, 0}))
      return false;
  }
  return true;
}

}  // namespace

bool triangle_box_overlap(const Vec3d& box_center, const Vec3d& box_half, const Vec3d& a, const Vec3d& b,
                          const Vec3d& c) {
  const Vec3d v0 = a - box_center, v1 = b - box_center, v2 = c - box_center;
  return for_each_axis(v0, v1, v2,
                       [&](Interval p, const Vec3d& n_abs) { return !separated(p, dot(box_half, n_abs)); });
}

namespace {

// Gap between 0 and the interval spanned by p0, p1 on an axis of L1 norm r,
// divided by r (0 when the interval holds 0 or the axis is degenerate).
inline double edge_axis_gap(double p0, double p1, double r) {
  const double gap = std::max(std::min(p0, p1), -std::max(p0, p1));
  return gap > 0 && r > 0 ? gap / r : 0;
}

// The nine edge x box-axis gaps for edge e, with `a` on the edge and `o` the
// opposite corner (both edge endpoints project to the same value).
inline double edge_gaps(const Vec3d& e, const Vec3d& a, const Vec3d& o) {
  const double ax = std::fabs(e.x), ay = std::fabs(e.y), az = std::fabs(e.z);
  double d = edge_axis_gap(a.y * e.z - a.z * e.y, o.y * e.z - o.z * e.y, ay + az);
  d = std::max(d, edge_axis_gap(a.z * e.x - a.x * e.z, o.z * e.x - o.x * e.z, ax + az));
  return std::max(d, edge_axis_gap(a.x * e.y - a.y * e.x, o.x * e.y - o.y * e.x, ax + ay));
}

}  // namespace

double triangle_linf_distance_relative(const Vec3d& v0, const Vec3d& v1, const Vec3d& v2) {
  double d = triangle_box_axes_gap(v0, v1, v2);
  const Vec3d e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
  // Triangle normal: all corners project alike up to rounding; use all three.
  const Vec3d n = cross(e0, e1);
  const double p0 = dot(v0, n), p1 = dot(v1, n), p2 = dot(v2, n);
  const double r = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  const double gap = std::max(std::min(std::min(p0, p1), p2), -std::max(std::max(p0, p1), p2));
  if (gap > 0 && r > 0) d = std::max(d, gap / r);
  d = std::max(d, edge_gaps(e0, v0, v2));
  d = std::max(d, edge_gaps(e1, v1, v0));
  return std::max(d, edge_gaps(e2, v2, v1));
}

double triangle_linf_distance(const Vec3d& point, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return triangle_linf_distance_relative(a - point, b - point, c - point);
}

}  // namespace cellbake
