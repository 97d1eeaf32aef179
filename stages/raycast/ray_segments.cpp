// Slab test for the open box interval: Kay & Kajiya 1986, "Ray tracing complex
// scenes", SIGGRAPH.
#include "stages/raycast/ray_segments.h"

#include <algorithm>
#include <cmath>

namespace cellbake {

EyeBox eye_relative_box(const Box3d& box, const Vec3d& eye) {
  EyeBox b;
  if (box.empty()) return b;
  for (int k = 0; k < 3; ++k)
    if (!(box.lo[k] < box.hi[k])) return b;
  b.lo = box.lo - eye;
  b.hi = box.hi - eye;
  b.none = false;
  return b;
}

RaySegments ray_segments(const Vec3d& dir, const EyeBox& box, double near) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  RaySegments s;
  s.t0 = static_cast<float>(near);
  if (box.none) return s;
  // The open interval (t_in, t_out) of t with eye + t dir strictly inside.
  double t_in = -inf, t_out = inf;
  for (int k = 0; k < 3; ++k) {
    if (dir[k] == 0) {
      if (!(box.lo[k] < 0 && 0 < box.hi[k])) return s;  // never strictly inside this slab
      continue;
    }
    const double a = box.lo[k] / dir[k], b = box.hi[k] / dir[k];
    t_in = std::max(t_in, std::min(a, b));
    t_out = std::min(t_out, std::max(a, b));
  }
  if (!(t_in < t_out) || t_out <= near) return s;  // the ray misses the interior beyond the near plane
  const float leave = std::nextafter(static_cast<float>(t_out), 0.0f);
  if (t_in < near) {  // inside at the near plane: start where it leaves
    s.t0 = std::max(static_cast<float>(near), leave);
    return s;
  }
  s.t1 = std::nextafter(static_cast<float>(t_in), static_cast<float>(inf));
  s.two = true;
  s.t2 = leave;
  return s;
}

}  // namespace cellbake
