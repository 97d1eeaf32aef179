#include "pipeline/scenes/scene_math.h"

#include <cmath>

namespace cellbake {
namespace {

constexpr double kHalfPi = 1.57079632679489661923;

// Taylor series of sin and cos on [0, pi/4] in nested (Horner) form, ten terms
// each: the first omitted term is below 1e-21.
SinCos sin_cos_small(double x) {
  const double x2 = x * x;
  double s = 1.0, c = 1.0;
  for (int n = 10; n >= 1; --n) {
    s = 1.0 - x2 / static_cast<double>((2 * n) * (2 * n + 1)) * s;
    c = 1.0 - x2 / static_cast<double>((2 * n - 1) * (2 * n)) * c;
  }
  return {x * s, c};
}

}  // namespace

SinCos sin_cos_turns(double turns) {
  const double quarters = turns * 4.0;
  const double q = std::floor(quarters);
  const double r = quarters - q;  // position inside the quarter, [0, 1)
  SinCos in_quarter;
  if (r <= 0.5) {
    in_quarter = sin_cos_small(r * kHalfPi);
  } else {
    const SinCos mirrored = sin_cos_small((1.0 - r) * kHalfPi);
    in_quarter = {mirrored.c, mirrored.s};
  }
  switch (static_cast<long long>(q) & 3) {
    case 0:
      return in_quarter;
    case 1:
      return {in_quarter.c, -in_quarter.s};
    case 2:
      return {-in_quarter.s, -in_quarter.c};
    default:
      return {-in_quarter.c, in_quarter.s};
  }
}

Vec3d any_perpendicular(Vec3d t) {
  const double ax = std::fabs(t.x), ay = std::fabs(t.y), az = std::fabs(t.z);
  Vec3d helper = (ax <= ay && ax <= az) ? Vec3d{1, 0, 0} : (ay <= az ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1});
  return normalized(cross(t, helper));
}

Vec3d rotate_about(Vec3d v, Vec3d axis, SinCos angle) {
  return v * angle.c + cross(axis, v) * angle.s + axis * (dot(axis, v) * (1.0 - angle.c));
}

}  // namespace cellbake
