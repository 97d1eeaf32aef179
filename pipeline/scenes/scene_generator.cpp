// Procedural test scenes (see scene_generator.h). Before emitting anything the
// generator searches the scene density (SceneDensity) with exact triangle
// counts from counting passes of the same layout code, so the scene is built
// once, at the density whose count is nearest the target.
#include "pipeline/scenes/scene_generator.h"

#include <cmath>
#include <stdexcept>

#include "pipeline/scenes/scene_builder.h"
#include "pipeline/scenes/scene_city.h"
#include "pipeline/scenes/scene_house.h"
#include "pipeline/scenes/scene_plant.h"

namespace cellbake {
namespace {

constexpr double kMaxDetail = 1u << 20;
constexpr double kMaxTessellationBoost = 256;  // phase 2 range, as a factor over phase 1's density
constexpr std::uint64_t kPartTriangles = 100'000;

void build_scene(SceneKind kind, const SceneDensity& density, std::uint64_t seed, SceneBuilder& out) {
  switch (kind) {
    case SceneKind::plant:
      build_plant_scene(density, seed, out);
      return;
    case SceneKind::house:
      build_house_scene(density, seed, out);
      return;
    case SceneKind::city:
      build_city_scene(density, seed, out);
      return;
  }
  throw std::invalid_argument("generate_scene: unknown scene kind");
}

std::uint64_t count_triangles(const SceneParams& params, const SceneDensity& density) {
  SceneBuilder counter;
  build_scene(params.kind, density, params.seed, counter);
  return counter.triangles();
}

struct Bracket {
  SceneDensity below, above;  // counts <= target and > target
  std::uint64_t count_below = 0, count_above = 0;
};

// Bisects (on a log scale) the density returned by `at(x)` for x in [lo, hi],
// where count(at(lo)) <= target < count(at(hi)); stops when the two counts are
// within 0.2 % of the target of each other.
template <typename DensityAt>
Bracket bisect(const SceneParams& params, DensityAt at, double lo, double hi, std::uint64_t count_lo,
               std::uint64_t count_hi) {
  const std::uint64_t target = params.target_triangles;
  for (int iteration = 0; iteration < 60 && hi > lo * (1 + 1e-12); ++iteration) {
    if (static_cast<double>(count_hi - count_lo) <= 0.002 * static_cast<double>(target)) break;
    const double mid = std::sqrt(lo * hi);
    const std::uint64_t count = count_triangles(params, at(mid));
    if (count <= target) {
      lo = mid;
      count_lo = count;
    } else {
      hi = mid;
      count_hi = count;
    }
  }
  return {at(lo), at(hi), count_lo, count_hi};
}

// The density whose exact triangle count is nearest the target. Phase 1 raises
// structure and tessellation together (doubling, then bisection); object
// counts change in steps, so phase 2 keeps phase 1's structure below the target
// and raises only tessellation, whose steps are per object and small. Targets
// below a scene's minimum give the minimum, above its maximum the maximum.
SceneDensity choose_density(const SceneParams& params) {
  const std::uint64_t target = params.target_triangles;
  auto together = [](double d) { return SceneDensity{d, d}; };
  double lo = 1;
  std::uint64_t count_lo = count_triangles(params, together(lo));
  if (count_lo >= target) return together(lo);
  double hi = lo;
  std::uint64_t count_hi = count_lo;
  while (count_hi <= target) {
    if (hi >= kMaxDetail) return together(hi);
    lo = hi;
    count_lo = count_hi;
    hi = std::min(hi * 2, kMaxDetail);
    count_hi = count_triangles(params, together(hi));
  }
  const Bracket phase1 = bisect(params, together, lo, hi, count_lo, count_hi);
  Bracket best = phase1;
  const double structure = phase1.below.structure;
  auto finer = [structure](double t) { return SceneDensity{structure, t}; };
  const double t_hi = std::min(structure * kMaxTessellationBoost, kMaxDetail);
  const std::uint64_t count_t_hi = count_triangles(params, finer(t_hi));
  if (count_t_hi > target) {
    const Bracket phase2 = bisect(params, finer, structure, t_hi, phase1.count_below, count_t_hi);
    best.below = phase2.below;
    best.count_below = phase2.count_below;
    if (phase2.count_above < best.count_above) {
      best.above = phase2.above;
      best.count_above = phase2.count_above;
    }
  } else {
    best.below = finer(t_hi);
    best.count_below = count_t_hi;
  }
  return target - best.count_below <= best.count_above - target ? best.below : best.above;
}

}  // namespace

SceneKind parse_scene_kind(const std::string& name) {
  if (name == "plant") return SceneKind::plant;
  if (name == "house") return SceneKind::house;
  if (name == "city") return SceneKind::city;
  throw std::invalid_argument("unknown scene kind '" + name + "' (expected plant, house or city)");
}

SceneSummary generate_scene(const SceneParams& params, const std::function<void(const TriangleMesh&)>& emit) {
  const SceneDensity density = choose_density(params);
  SceneBuilder builder(emit, kPartTriangles);
  build_scene(params.kind, density, params.seed, builder);
  return builder.finish();
}

}  // namespace cellbake
