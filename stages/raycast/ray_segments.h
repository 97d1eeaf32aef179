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
#include <span>
#include <vector>

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

// The open interval (lo, hi) of t where eye + t * dir is strictly inside one
// slab (axis) of an EyeBox: lo >= hi when never (a ray parallel to the slab
// outside it), (-inf, inf) when always (parallel and inside).
struct SlabInterval {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  // A slab no ray point is inside: with it, ray_segments gives [near, inf).
  static constexpr SlabInterval never() {
    return {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  }
};

// The slab [box_lo, box_hi] (eye-relative) for a ray with component `d` on
// its axis; `inverse` = 1.0 / d, read only when d != 0.
inline SlabInterval slab_interval(double d, double inverse, double box_lo, double box_hi) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  if (d == 0) return box_lo < 0 && 0 < box_hi ? SlabInterval{-inf, inf} : SlabInterval::never();
  const double a = box_lo * inverse, b = box_hi * inverse;
  return {std::min(a, b), std::max(a, b)};
}

// The segments of a ray at t >= near (near > 0) outside the open box whose
// three slabs it crosses in `x`, `y` and `z` (slab_interval; an
// EyeBox::none is SlabInterval::never() on any axis). Segment ends on the box boundary are widened by one
// float step, so surfaces lying on the boundary (kept by the GL path) are not
// lost to rounding.
inline RaySegments ray_segments(const SlabInterval& x, const SlabInterval& y, const SlabInterval& z,
                                double near) {
  // One float step towards zero / towards infinity, for positive finite floats.
  const auto step_down = [](float f) { return f > 0 ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) - 1) : f; };
  const auto step_up = [](float f) {
    return f >= 0 && f < std::numeric_limits<float>::max() ? std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) + 1) : f;
  };
  RaySegments s;
  s.t0 = static_cast<float>(near);
  // The open interval (t_in, t_out) of t with eye + t dir strictly inside.
  const double t_in = std::max(std::max(x.lo, y.lo), z.lo), t_out = std::min(std::min(x.hi, y.hi), z.hi);
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

// The segments of the ray eye + t * dir (dir finite and non-zero, near > 0)
// outside the open box `box` and at t >= near, as above.
inline RaySegments ray_segments(const Vec3d& dir, const EyeBox& box, double near) {
  if (box.none) return ray_segments(SlabInterval::never(), {}, {}, near);
  SlabInterval slab[3];
  for (int k = 0; k < 3; ++k)
    slab[k] = slab_interval(dir[k], dir[k] != 0 ? 1.0 / dir[k] : 0.0, box.lo[k], box.hi[k]);
  return ray_segments(slab[0], slab[1], slab[2], near);
}

// The box's slabs along the rays of one cube face, by pixel. A ray's
// direction cube_face_direction(b, s, t) has components +-1 (on the face's
// forward axis), +-s (right axis) and +-t (up axis), so the forward slab is
// the same for every ray of the face, the right one depends on the pixel's
// column only and the up one on its row only: a face's segments cost a
// min and a max per ray after 2 size slab tests.
class FaceSlabs {
 public:
  // For face `b`, `box`, and coordinate[i] = s of column i = -t of row i
  // (inverse_coordinate[i] = 1.0 / coordinate[i]; the spans the same size).
  void set(const FaceBasis& b, const EyeBox& box, std::span<const double> coordinate,
           std::span<const double> inverse_coordinate);
  // ray_segments(cube_face_direction(b, coordinate[col], -coordinate[row]), box, near),
  // the same bits.
  RaySegments segments(std::size_t col, std::size_t row, double near) const {
    return ray_segments(forward_, columns_[col], rows_[row], near);
  }

 private:
  SlabInterval forward_;  // never() for an EyeBox::none
  std::vector<SlabInterval> columns_, rows_;
};

}  // namespace cellbake
