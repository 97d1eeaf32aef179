#include "runner/verify/verify_views.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "stages/sample/sample_points.h"

namespace cellbake {
namespace {

int up_index(const Vec3d& up) {
  for (int a = 0; a < 3; ++a)
    if (up[a] == 1 && up[(a + 1) % 3] == 0 && up[(a + 2) % 3] == 0) return a;
  throw std::invalid_argument("verify views: up must be a coordinate axis");
}

// SplitMix64: a tiny, portable, seeded generator (std distributions differ between libraries).
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
};

// The horizontal unit direction at `yaw` radians around the up axis `u`.
Vec3d yaw_direction(double yaw, int u) {
  Vec3d dir;
  dir[(u + 1) % 3] = std::cos(yaw);
  dir[(u + 2) % 3] = std::sin(yaw);
  return dir;
}

}  // namespace

const char* view_kind_name(VerifyViewKind kind) {
  switch (kind) {
    case VerifyViewKind::random:
      return "random";
    case VerifyViewKind::centre:
      return "centre";
    case VerifyViewKind::corner:
      return "corner";
    case VerifyViewKind::sample:
      return "sample";
  }
  return "random";
}

VerifyViewKind parse_view_kind(const std::string& name) {
  if (name == "random") return VerifyViewKind::random;
  if (name == "centre") return VerifyViewKind::centre;
  if (name == "corner") return VerifyViewKind::corner;
  if (name == "sample") return VerifyViewKind::sample;
  throw std::invalid_argument("verify views: unknown view kind \"" + name + "\"");
}

Vec3d golden_angle_direction(int k, const Vec3d& up) {
  constexpr double kGoldenAngle = 137.50776405003785 * std::numbers::pi / 180.0;
  return yaw_direction(std::fmod(k * kGoldenAngle, 2 * std::numbers::pi), up_index(up));
}

std::vector<VerifyViewPlan> plan_verify_views(const Box3d& cell, const Box3d& navigable, const Vec3d& up,
                                              int random_views, bool reference_views, std::uint64_t seed) {
  if (random_views < 1) throw std::invalid_argument("verify views: need at least one random view per cell");
  if (cell.empty() || !is_finite(cell.lo) || !is_finite(cell.hi))
    throw std::invalid_argument("verify views: empty or non-finite cell bounds");
  if (navigable.empty() || !is_finite(navigable.lo) || !is_finite(navigable.hi))
    throw std::invalid_argument("verify views: empty or non-finite navigable part");
  const int u = up_index(up);
  const Vec3d e = cell.extent();
  const double size = std::max({e.x, e.y, e.z});

  std::vector<VerifyViewPlan> views;
  SplitMix64 rng{seed};
  for (int k = 0; k < random_views; ++k) {
    Vec3d p;
    for (int axis = 0; axis < 3; ++axis)
      p[axis] = std::min(navigable.hi[axis], navigable.lo[axis] + rng.uniform() * navigable.extent()[axis]);
    const Vec3d dir = yaw_direction(rng.uniform() * 2 * std::numbers::pi, u);
    views.push_back({VerifyViewKind::random, p, p + dir * size});
  }
  if (reference_views) {
    const Vec3d c = navigable.center();
    const auto add = [&](VerifyViewKind kind, const Vec3d& p) {
      views.push_back({kind, p, p + golden_angle_direction(int(views.size()), up) * size});
    };
    add(VerifyViewKind::centre, c);
    for (const Vec3d& corner : initial_sample_points(navigable, InitialSamples::corners)) {
      if (corner == c) continue;  // a point-sized part has no corners apart from its centre
      Vec3d p = corner;
      for (int axis = 0; axis < 3; ++axis) {
        const double inset = std::min(0.01 * size, 0.5 * navigable.extent()[axis]);
        p[axis] += p[axis] < c[axis] ? inset : p[axis] > c[axis] ? -inset : 0;
      }
      add(VerifyViewKind::corner, p);
    }
  }
  return views;
}

}  // namespace cellbake
