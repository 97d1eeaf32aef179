// Exact triangle / axis-aligned box overlap and the Chebyshev (L-infinity)
// distance from a point to a triangle, in double precision.
//
// Reference: T. Akenine-Möller, "Fast 3D Triangle-Box Overlap Testing",
// Journal of Graphics Tools 6(1):29-33, 2001 — the separating-axis test over
// 13 axes (3 box face normals, the triangle normal, 9 edge x box-axis cross
// products).
#pragma once

#include <algorithm>

#include "stages/geometry.h"

namespace cellbake {

// True when the closed triangle (a, b, c) and the closed axis-aligned box with
// centre `box_center` and per-axis half extents `box_half` (each >= 0) share at
// least one point; touching counts. Degenerate triangles (segments, points) are
// handled exactly: their zero-length axes are skipped, which keeps the test
// exact. Deterministic; no allocation.
bool triangle_box_overlap(const Vec3d& box_center, const Vec3d& box_half, const Vec3d& a, const Vec3d& b,
                          const Vec3d& c);

// Chebyshev distance from `point` to the closed triangle (a, b, c):
// min over x in the triangle of max_i |x_i - point_i|, i.e. the smallest h >= 0
// such that the closed cube of half size h centred at `point` touches the
// triangle. Cubes centred at the point are nested, so the triangle intersects
// cube(point, h) exactly when h >= triangle_linf_distance(point, ...).
//
// Computed in closed form from the same 13 separating axes: for a cube of half
// size h the box radius on axis n is h * |n|_1, so the triangle is separated on
// n exactly while h < gap_n / |n|_1, where gap_n is the distance from the cube
// centre to the triangle's projected interval. The distance is the maximum of
// these ratios (and 0). Rounding error is a few ulps of the coordinates'
// magnitude relative to `point`. Deterministic.
double triangle_linf_distance(const Vec3d& point, const Vec3d& a, const Vec3d& b, const Vec3d& c);

// Same, with the corners already given relative to the point (v = corner - point).
double triangle_linf_distance_relative(const Vec3d& v0, const Vec3d& v1, const Vec3d& v2);

// A cheap lower bound of triangle_linf_distance_relative: the Chebyshev
// distance from the point to the triangle's bounding box (the 3 box-face axes
// alone). Corners relative to the point.
// Inline: the cull box evaluates it for every triangle of every chunk it loads.
inline double triangle_box_axes_gap(const Vec3d& v0, const Vec3d& v1, const Vec3d& v2) {
  double d = 0;
  d = std::max(d, std::max(std::min(std::min(v0.x, v1.x), v2.x), -std::max(std::max(v0.x, v1.x), v2.x)));
  d = std::max(d, std::max(std::min(std::min(v0.y, v1.y), v2.y), -std::max(std::max(v0.y, v1.y), v2.y)));
  d = std::max(d, std::max(std::min(std::min(v0.z, v1.z), v2.z), -std::max(std::max(v0.z, v1.z), v2.z)));
  return d;
}

// Chebyshev distance from `point` to the closed box: the smallest h >= 0 such
// that cube(point, h) touches `box` (0 when the point is inside). Undefined for
// an empty box.
inline double box_linf_distance(const Vec3d& point, const Box3d& box) {
  double d = 0;
  for (int i = 0; i < 3; ++i) d = std::max({d, box.lo[i] - point[i], point[i] - box.hi[i]});
  return d;
}

// The smallest h such that cube(point, h) contains `box`: the Chebyshev
// distance from the point to the box's farthest corner. Undefined for an empty box.
inline double box_linf_reach(const Vec3d& point, const Box3d& box) {
  double d = 0;
  for (int i = 0; i < 3; ++i) d = std::max({d, box.hi[i] - point[i], point[i] - box.lo[i]});
  return d;
}

}  // namespace cellbake
