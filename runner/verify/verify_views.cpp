#include "runner/verify/verify_views.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

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

}  // namespace

const char* view_kind_name(VerifyViewKind kind) {
  switch (kind) {
    case VerifyViewKind::centre: return "centre";
    case VerifyViewKind::corner: return "corner";
    case VerifyViewKind::interior: return "interior";
    case VerifyViewKind::sample: return "sample";
  }
  return "centre";
}

VerifyViewKind parse_view_kind(const std::string& name) {
  if (name == "centre") return VerifyViewKind::centre;
  if (name == "corner") return VerifyViewKind::corner;
  if (name == "interior") return VerifyViewKind::interior;
  if (name == "sample") return VerifyViewKind::sample;
  throw std::invalid_argument("verify views: unknown view kind \"" + name + "\"");
}

std::vector<VerifyViewPlan> plan_verify_views(const Box3d& bounds, bool flat, const Vec3d& up, int count,
                                              std::uint64_t seed) {
  if (count < 1) throw std::invalid_argument("verify views: need at least one view per cell");
  if (bounds.empty()) throw std::invalid_argument("verify views: empty cell bounds");
  const int u = up_index(up), a = (u + 1) % 3, b = (u + 2) % 3;
  const Vec3d c = bounds.center();
  const Vec3d e = bounds.extent();
  const double size = std::max({e.x, e.y, e.z});
  const double inset = 0.01 * size;

  std::vector<std::pair<VerifyViewKind, Vec3d>> points{{VerifyViewKind::centre, c}};
  const int up_layers = flat ? 1 : 2;
  for (int k = 0; k < up_layers && int(points.size()) < count; ++k)
    for (int corner = 0; corner < 4 && int(points.size()) < count; ++corner) {
      Vec3d p = c;
      // Corners go round the square: (lo, lo), (hi, lo), (hi, hi), (lo, hi).
      const bool hi_a = corner == 1 || corner == 2, hi_b = corner >= 2;
      p[a] = hi_a ? bounds.hi[a] - inset : bounds.lo[a] + inset;
      p[b] = hi_b ? bounds.hi[b] - inset : bounds.lo[b] + inset;
      if (!flat) p[u] = k == 1 ? bounds.hi[u] - inset : bounds.lo[u] + inset;
      points.push_back({VerifyViewKind::corner, p});
    }
  SplitMix64 rng{seed};
  while (int(points.size()) < count) {
    Vec3d p = c;
    for (int axis = 0; axis < 3; ++axis) {
      const double t = rng.uniform();
      if (axis == u && flat) continue;
      p[axis] = bounds.lo[axis] + inset + t * (e[axis] - 2 * inset);
    }
    points.push_back({VerifyViewKind::interior, p});
  }

  std::vector<VerifyViewPlan> views;
  constexpr double kGoldenAngle = 137.50776405003785 * 3.14159265358979323846 / 180.0;
  for (int k = 0; k < count; ++k) {
    const double yaw = std::fmod(k * kGoldenAngle, 2 * 3.14159265358979323846);
    Vec3d dir;
    dir[a] = std::cos(yaw);
    dir[b] = std::sin(yaw);
    views.push_back({points[k].first, points[k].second, points[k].second + dir * size});
  }
  return views;
}

bool region_is_flat(const Box3d& region, const Vec3d& up, double cell_size) {
  return dot(region.extent(), up) < cell_size;
}

}  // namespace cellbake
