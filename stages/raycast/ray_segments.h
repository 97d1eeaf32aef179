// Where a sampling ray may hit geometry: from the near plane on, except where
// it runs strictly inside the discard (cull) box. This replaces the GL path's
// near-plane clipping and per-fragment discard exactly: a ray from the eye
// meets the open box in one open interval (t_in, t_out) (slab test, Kay &
// Kajiya 1986, "Ray tracing complex scenes", SIGGRAPH), so what is left of
// [near, inf) is at most two closed segments. Rays are parametrised as
// eye + t * dir with dir = cube_face_direction() (forward component 1), so t
// is the planar view depth and the near plane is t = near.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

#include "stages/cube_map.h"
#include "stages/geometry.h"

namespace cellbake {

// One or two segments [t0, t1] and, when `two`, [t2, inf).
struct RaySegments {
  float t0 = 0, t1 = std::numeric_limits<float>::infinity();
  bool two = false;
  float t2 = std::numeric_limits<float>::infinity();
};

// The box relative to the eye, with an empty flag (an empty box or one with
// no interior discards nothing).
struct EyeBox {
  Vec3d lo, hi;
  bool none = true;
};

// `box` (world) relative to `eye`; none when it is empty or flat on an axis.
EyeBox eye_relative_box(const Box3d& box, const Vec3d& eye);

// The segments of the ray eye + t * dir (dir finite and non-zero, near > 0)
// outside the open box `box` and at t >= near. Segment ends on the box
// boundary are widened by one float step, so surfaces lying on the boundary
// (kept by the GL path) are not lost to rounding. Inline: the sampler calls it
// once per ray. `inverse` holds 1.0 / dir[k] for every non-zero dir[k] (the
// sampler knows them per pixel column and row: see face_ray_inverse).
inline RaySegments ray_segments(const Vec3d& dir, const Vec3d& inverse, const EyeBox& box, double near) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  // One float step towards zero / towards infinity, for positive finite floats.
  const auto step_down = [](float f) { return f > 0 ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) - 1) : f; };
  const auto step_up = [](float f) {
    return f >= 0 && f < std::numeric_limits<float>::max() ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) + 1) : f;
  };
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
    const double a = box.lo[k] * inverse[k], b = box.hi[k] * inverse[k];
    t_in = std::max(t_in, std::min(a, b));
    t_out = std::min(t_out, std::max(a, b));
  }
  if (!(t_in < t_out) || t_out <= near) return s;  // the ray misses the interior beyond the near plane
  const float leave = step_down(static_cast<float>(t_out));
  if (t_in < near) {  // inside at the near plane: start where it leaves
    s.t0 = std::max(static_cast<float>(near), leave);
    return s;
  }
  s.t1 = step_up(static_cast<float>(t_in));
  s.two = true;
  s.t2 = leave;
  return s;
}

// The same, dividing by dir's components here.
inline RaySegments ray_segments(const Vec3d& dir, const EyeBox& box, double near) {
  const auto inverse = [](double d) { return d != 0 ? 1.0 / d : 0.0; };  // 0 components are not read
  return ray_segments(dir, Vec3d{inverse(dir.x), inverse(dir.y), inverse(dir.z)}, box, near);
}

// 1.0 / d per non-zero component of d = cube_face_direction(b, s, t), from
// 1.0 / s and 1.0 / t: each component of d is exactly one of +-1, +-s, +-t
// (the basis vectors are signed unit axes), so these are the same bits.
inline Vec3d face_ray_inverse(const FaceBasis& b, double inverse_s, double inverse_t) {
  Vec3d out;
  for (int k = 0; k < 3; ++k)
    out[k] = b.forward[k] != 0 ? b.forward[k]
             : b.right[k] != 0 ? b.right[k] * inverse_s
                               : b.up[k] * inverse_t;
  return out;
}

}  // namespace cellbake
