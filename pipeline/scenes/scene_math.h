// Small deterministic vector math for the procedural scenes. The trigonometry
// is our own polynomial (no libm), so circle points come out bit-identical on
// every machine with IEEE doubles.
#pragma once

#include "stages/geometry.h"

namespace cellbake {

struct SinCos {
  double s = 0, c = 1;
};

// sin and cos of the angle `turns` * 2 pi, for turns in [0, 1]. Exact at
// multiples of a quarter turn; otherwise within ~1 ulp of the true value.
SinCos sin_cos_turns(double turns);

// `v` scaled to unit length; `v` must be non-zero.
inline Vec3d normalized(Vec3d v) { return v * (1.0 / length(v)); }

// A unit vector perpendicular to unit vector `t` (deterministic choice).
Vec3d any_perpendicular(Vec3d t);

// `v` rotated about unit axis `axis` by the angle whose sine/cosine are given (Rodrigues).
Vec3d rotate_about(Vec3d v, Vec3d axis, SinCos angle);

}  // namespace cellbake
