// Where a sampling ray may hit geometry: from the near plane on, except where
// it runs strictly inside the discard (cull) box. This replaces the GL path's
// near-plane clipping and per-fragment discard exactly: a ray from the eye
// meets the open box in one open interval (t_in, t_out) (slab test, Kay &
// Kajiya 1986, "Ray tracing complex scenes", SIGGRAPH), so what is left of
// [near, inf) is at most two closed segments. Rays are parametrised as
// eye + t * dir with dir = cube_face_direction() (forward component 1), so t
// is the planar view depth and the near plane is t = near.
#pragma once

#include <limits>

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
// (kept by the GL path) are not lost to rounding.
RaySegments ray_segments(const Vec3d& dir, const EyeBox& box, double near);

}  // namespace cellbake
