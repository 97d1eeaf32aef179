// Tests for stages/triangle_box_overlap and stages/cull_box: the separating-axis
// test against an independent polygon-clipping reference, the Chebyshev
// distance against the test, and the cull-box search on analytic scenes, hard
// cases and random scenes checked by brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "stages/cull_box.h"
#include "stages/triangle_box_overlap.h"
#include "tests/fixture_memory_chunk_source.h"

namespace cellbake {
namespace {

using Tri = std::array<Vec3d, 3>;

// Independent reference: clip the triangle polygon by the six box half-spaces
// (Sutherland-Hodgman); the triangle meets the box when anything is left.
bool clipped_overlap(const Box3d& box, const Tri& t) {
  std::vector<Vec3d> poly(t.begin(), t.end());
  for (int axis = 0; axis < 3 && !poly.empty(); ++axis) {
    for (int side = 0; side < 2 && !poly.empty(); ++side) {
      auto inside = [&](const Vec3d& p) {
        return side == 0 ? p[axis] >= box.lo[axis] : p[axis] <= box.hi[axis];
      };
      const double plane = side == 0 ? box.lo[axis] : box.hi[axis];
      std::vector<Vec3d> out;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3d& a = poly[i];
        const Vec3d& b = poly[(i + 1) % poly.size()];
        if (inside(a)) out.push_back(a);
        if (inside(a) != inside(b)) {
          const double s = (plane - a[axis]) / (b[axis] - a[axis]);
          Vec3d p = a + (b - a) * s;
          p[axis] = plane;
          out.push_back(p);
        }
      }
      poly.swap(out);
    }
  }
  return !poly.empty();
}

Box3d grow(const Box3d& b, double e) { return {b.lo - Vec3d{e, e, e}, b.hi + Vec3d{e, e, e}}; }

Tri random_triangle(std::mt19937_64& rng, double spread, double size) {
  std::uniform_real_distribution<double> pos(-spread, spread), off(-size, size);
  const Vec3d a{pos(rng), pos(rng), pos(rng)};
  Tri t{a, a + Vec3d{off(rng), off(rng), off(rng)}, a + Vec3d{off(rng), off(rng), off(rng)}};
  std::uniform_int_distribution<int> kind(0, 9);
  const int k = kind(rng);
  if (k == 0) t[2] = t[1];                         // segment
  if (k == 1) t[1] = t[2] = t[0];                  // point
  if (k == 2) t[2] = t[0] + (t[1] - t[0]) * 0.37;  // collinear
  if (k == 3) t[1].x = t[0].x, t[2].x = t[0].x;    // axis-aligned plane
  if (k == 4) t[1].y = t[0].y, t[1].z = t[0].z;    // edge parallel to x
  return t;
}

TEST(TriangleBoxOverlap, AgreesWithPolygonClippingOnRandomCases) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> half(0.05, 1.5);
  int overlaps = 0, misses = 0;
  for (int i = 0; i < 100000; ++i) {
    const Tri t = random_triangle(rng, 3.0, 2.0);
    const Vec3d c{0, 0, 0};
    const Vec3d h{half(rng), half(rng), half(rng)};
    const Box3d box{c - h, c + h};
    const bool sat = triangle_box_overlap(c, h, t[0], t[1], t[2]);
    // Decide only cases that are clear of the boundary by 1e-9.
    if (clipped_overlap(grow(box, -1e-9), t)) {
      EXPECT_TRUE(sat) << "case " << i;
      ++overlaps;
    } else if (!clipped_overlap(grow(box, 1e-9), t)) {
      EXPECT_FALSE(sat) << "case " << i;
      ++misses;
    }
  }
  EXPECT_GT(overlaps, 5000);
  EXPECT_GT(misses, 10000);
}

TEST(TriangleBoxOverlap, SampledInteriorPointsImplyOverlap) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 20000; ++i) {
    const Tri t = random_triangle(rng, 2.0, 2.0);
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const Vec3d p = t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b;
    const Vec3d h{0.01 + u(rng), 0.01 + u(rng), 0.01 + u(rng)};
    const Vec3d c = p + Vec3d{(u(rng) - 0.5) * h.x, (u(rng) - 0.5) * h.y, (u(rng) - 0.5) * h.z};
    EXPECT_TRUE(triangle_box_overlap(c, h, t[0], t[1], t[2])) << "case " << i;
  }
}

TEST(TriangleBoxOverlap, TouchingCountsAndHandBuiltCases) {
  const Vec3d c{0, 0, 0}, h{1, 1, 1};
  // A triangle lying in the plane x = 1 touches the face.
  EXPECT_TRUE(triangle_box_overlap(c, h, {1, 0, 0}, {1, 5, 0}, {1, 0, 5}));
  EXPECT_FALSE(triangle_box_overlap(c, h, {1.0000001, 0, 0}, {1.0000001, 5, 0}, {1.0000001, 0, 5}));
  // A big triangle around the box, cutting through it (no vertex inside).
  EXPECT_TRUE(triangle_box_overlap(c, h, {-100, -100, 0.5}, {100, -100, 0.5}, {0, 100, 0.5}));
  // Near a corner: the plane x + y + z = 3 touches corner (1,1,1); 3.01 misses it.
  EXPECT_TRUE(triangle_box_overlap(c, h, {3, 0, 0}, {0, 3, 0}, {0, 0, 3}));
  EXPECT_FALSE(triangle_box_overlap(c, h, {3.01, 0, 0}, {0, 3.01, 0}, {0, 0, 3.01}));
  // Edge-edge separation: a segment passing diagonally just past an edge.
  EXPECT_FALSE(triangle_box_overlap(c, h, {2.05, 0, -5}, {0, 2.05, -5}, {0, 2.05, 5}));
  EXPECT_TRUE(triangle_box_overlap(c, h, {1.95, 0, -5}, {0, 1.95, -5}, {0, 1.95, 5}));
}

TEST(TriangleLinfDistance, MatchesSeparatingAxisTestAtThreshold) {
  std::mt19937_64 rng(3);
  int positive = 0;
  for (int i = 0; i < 100000; ++i) {
    const Tri t = random_triangle(rng, 5.0, 3.0);
    std::uniform_real_distribution<double> pos(-5, 5);
    const Vec3d p{pos(rng), pos(rng), pos(rng)};
    const double d = triangle_linf_distance(p, t[0], t[1], t[2]);
    ASSERT_GE(d, 0);
    const double above = d * (1 + 1e-9) + 1e-12, below = d * (1 - 1e-9) - 1e-12;
    EXPECT_TRUE(triangle_box_overlap(p, {above, above, above}, t[0], t[1], t[2])) << "case " << i;
    if (below > 0) {
      ++positive;
      EXPECT_FALSE(triangle_box_overlap(p, {below, below, below}, t[0], t[1], t[2])) << "case " << i;
    }
  }
  EXPECT_GT(positive, 80000);
}

TEST(TriangleLinfDistance, IsALowerBoundOfSampledPointsAndIsApproached) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 300; ++i) {
    const Tri t = random_triangle(rng, 3.0, 3.0);
    const Vec3d p{u(rng) * 4 - 2, u(rng) * 4 - 2, u(rng) * 4 - 2};
    const double d = triangle_linf_distance(p, t[0], t[1], t[2]);
    double best = std::numeric_limits<double>::infinity();
    const int n = 200;
    for (int a = 0; a <= n; ++a)
      for (int b = 0; a + b <= n; ++b) {
        const Vec3d x = t[0] + (t[1] - t[0]) * (double(a) / n) + (t[2] - t[0]) * (double(b) / n);
        best = std::min(best, std::max({std::fabs(x.x - p.x), std::fabs(x.y - p.y), std::fabs(x.z - p.z)}));
      }
    EXPECT_LE(d, best + 1e-12) << "case " << i;
    // The sampling grid spacing is at most |edge| / n <= 0.06 here.
    EXPECT_GE(d, best - 0.07) << "case " << i;
  }
}

TEST(TriangleLinfDistance, AnalyticValues) {
  const Vec3d o{0, 0, 0};
  EXPECT_DOUBLE_EQ(triangle_linf_distance(o, {2, -1, 3}, {2, 1, 3}, {2, 0, -3}), 2.0);  // face-on plane x = 2
  EXPECT_DOUBLE_EQ(triangle_linf_distance(o, {3, 0, 0}, {0, 3, 0}, {0, 0, 3}),
                   1.0);  // touches cube corner (1,1,1)
  EXPECT_DOUBLE_EQ(triangle_linf_distance(o, {-5, -5, 0}, {5, -5, 0}, {0, 5, 0}), 0.0);  // through the point
  EXPECT_DOUBLE_EQ(triangle_linf_distance(o, {4, 4, 4}, {4, 4, 4}, {4, 4, 4}), 4.0);     // a point
  EXPECT_DOUBLE_EQ(triangle_linf_distance(o, {2, 0, -9}, {0, 2, -9}, {0, 2, 9}),
                   1.0);  // edge-edge: x + y = 2 meets the cube edge at (1,1)
}

// ---------------------------------------------------------------- cull box

// Triangles indexed by lattice point p = (i + 0.5, j + 0.5, k + 0.5) - shift,
// i, j, k in [0, 2n); each triangle has p as its nearest point to `shift`'s
// origin, so its Chebyshev distance to the centre `offset` is exactly |p|_inf.
struct LatticeScene {
  test::MemoryChunkSource source;
  std::vector<Tri> triangles;
};

std::unique_ptr<LatticeScene> lattice_scene(int n, int block, const Vec3d& offset) {
  auto scene = std::make_unique<LatticeScene>();
  const double delta = 1.0 / 1024;
  std::map<std::array<int, 3>, std::vector<Tri>> blocks;
  for (int i = 0; i < 2 * n; ++i)
    for (int j = 0; j < 2 * n; ++j)
      for (int k = 0; k < 2 * n; ++k) {
        const Vec3d p{i + 0.5 - n, j + 0.5 - n, k + 0.5 - n};
        const Vec3d s{p.x > 0 ? 1.0 : -1.0, p.y > 0 ? 1.0 : -1.0, p.z > 0 ? 1.0 : -1.0};
        const Tri t{offset + p, offset + p + Vec3d{delta * s.x, 0, 0}, offset + p + Vec3d{0, delta * s.y, 0}};
        scene->triangles.push_back(t);
        blocks[{i / block, j / block, k / block}].push_back(t);
      }
  std::int64_t id = 1;
  for (const auto& [key, tris] : blocks) {
    const Vec3d origin =
        offset + Vec3d{double(key[0] * block - n), double(key[1] * block - n), double(key[2] * block - n)};
    scene->source.add(test::make_memory_chunk(id++, tris, origin));
  }
  return scene;
}

// Number of lattice triangles with |p|_inf <= h: (2 floor(h + 1/2))^3, capped.
std::uint64_t lattice_count(double h, int n) {
  const std::uint64_t m = std::min<std::uint64_t>(2 * n, 2 * static_cast<std::uint64_t>(std::floor(h + 0.5)));
  return m * m * m;
}

std::uint64_t brute_count(const std::vector<Tri>& tris, const Vec3d& c, double h) {
  std::uint64_t n = 0;
  for (const Tri& t : tris) n += triangle_box_overlap(c, {h, h, h}, t[0], t[1], t[2]);
  return n;
}

TEST(CullBox, LatticeSceneGivesTheAnalyticHalfSizeAndCount) {
  auto scene = lattice_scene(8, 4, {0, 0, 0});
  CullBoxParams params;
  params.triangle_budget = 1000;  // shells hold 8, 64, 216, 512, 1000, 1728, ... triangles
  params.min_half_size = 0.25;
  const CullBoxResult r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_NEAR(r.half_size, 5.5, 1e-9);
  EXPECT_LT(r.half_size, 5.5);
  EXPECT_EQ(r.triangle_count, 1000u);
  EXPECT_FALSE(r.budget_exceeded_at_min);
  EXPECT_EQ(brute_count(scene->triangles, {0, 0, 0}, r.half_size), 1000u);
  EXPECT_EQ(brute_count(scene->triangles, {0, 0, 0}, 5.5), 1728u);  // the next shell is at the boundary
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < r.near_field.size(); ++i) {
    sum += r.near_field[i].triangles;
    if (i > 0) {
      EXPECT_LT(r.near_field[i - 1].chunk_id, r.near_field[i].chunk_id);
    }
  }
  EXPECT_EQ(sum, r.triangle_count);
}

TEST(CullBox, EveryBudgetOnTheLatticeMatchesTheFormula) {
  auto scene = lattice_scene(6, 3, {0, 0, 0});
  for (std::uint64_t budget : {0ull, 7ull, 8ull, 63ull, 64ull, 500ull, 1727ull, 1728ull, 1729ull}) {
    CullBoxParams params;
    params.triangle_budget = budget;
    params.min_half_size = 0.1;
    const CullBoxResult r = find_cull_box({0, 0, 0}, params, scene->source);
    // Expected: the shell just past the budget, or the model extent when all fit.
    double expected = 5.5 + 1.0 / 1024;  // farthest corner of the model bounds
    for (int s = 0; s < 6; ++s)
      if (lattice_count(s + 0.5, 6) > budget) {
        expected = s + 0.5;
        break;
      }
    EXPECT_NEAR(r.half_size, expected, 1e-9) << "budget " << budget;
    EXPECT_EQ(r.triangle_count, lattice_count(r.half_size, 6)) << "budget " << budget;
    EXPECT_LE(r.triangle_count, budget);
  }
}

TEST(CullBox, SurveyCoordinatesKeepTheAnswer) {
  const Vec3d offset{512000.0, 6400000.0, 120.0};
  auto scene = lattice_scene(8, 4, offset);
  CullBoxParams params;
  params.triangle_budget = 1000;
  params.min_half_size = 0.25;
  const CullBoxResult r = find_cull_box(offset, params, scene->source);
  EXPECT_NEAR(r.half_size, 5.5, 1e-6);  // ulp(6.4e6) ~ 1e-9
  EXPECT_EQ(r.triangle_count, 1000u);
}

TEST(CullBox, EmptySceneReturnsTheMinimum) {
  test::MemoryChunkSource empty;
  CullBoxParams params;
  params.min_half_size = 0.5;
  const CullBoxResult r = find_cull_box({1, 2, 3}, params, empty);
  EXPECT_EQ(r.half_size, 0.5);
  EXPECT_EQ(r.triangle_count, 0u);
  EXPECT_TRUE(r.near_field.empty());
  EXPECT_FALSE(r.budget_exceeded_at_min);
  EXPECT_EQ(r.chunks_loaded, 0u);
}

TEST(CullBox, BudgetZeroStopsJustShortOfTheNearestTriangle) {
  auto scene = lattice_scene(4, 2, {0, 0, 0});
  CullBoxParams params;
  params.triangle_budget = 0;
  params.min_half_size = 0.1;
  const CullBoxResult r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_NEAR(r.half_size, 0.5, 1e-9);
  EXPECT_LT(r.half_size, 0.5);
  EXPECT_EQ(r.triangle_count, 0u);
  EXPECT_TRUE(r.near_field.empty());
  EXPECT_FALSE(r.budget_exceeded_at_min);
}

TEST(CullBox, BudgetAboveModelSizeReturnsTheModelExtent) {
  auto scene = lattice_scene(4, 2, {0, 0, 0});
  CullBoxParams params;
  params.triangle_budget = 100000;
  params.min_half_size = 0.5;
  const CullBoxResult r = find_cull_box({1, 0, 0}, params, scene->source);
  const Box3d b = scene->source.model_bounds();
  EXPECT_DOUBLE_EQ(r.half_size, box_linf_reach({1, 0, 0}, b));
  EXPECT_EQ(r.triangle_count, 512u);
  EXPECT_EQ(r.near_field.size(), scene->source.chunk_count());
  for (const NearChunk& c : r.near_field) EXPECT_TRUE(c.whole);
  EXPECT_EQ(r.chunks_loaded, 0u);  // every chunk is wholly inside: nothing to load
}

TEST(CullBox, MaxHalfSizeCapsAndMinHalfSizeFloors) {
  auto scene = lattice_scene(6, 3, {0, 0, 0});
  CullBoxParams params;
  params.triangle_budget = 1000000;
  params.min_half_size = 0.5;
  params.max_half_size = 3.0;
  CullBoxResult r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_EQ(r.half_size, 3.0);
  EXPECT_EQ(r.triangle_count, lattice_count(3.0, 6));  // 6^3
  EXPECT_FALSE(r.budget_exceeded_at_min);

  params.triangle_budget = 100;  // would give h just below 2.5 (216 > 100 >= 64)
  params.min_half_size = 3.0;    // but the cell itself is larger
  params.max_half_size = 10.0;
  r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_EQ(r.half_size, 3.0);
  EXPECT_TRUE(r.budget_exceeded_at_min);
  EXPECT_EQ(r.triangle_count, 216u);

  params.min_half_size = 2.0;  // floor below the answer: no effect
  r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_NEAR(r.half_size, 2.5, 1e-9);
  EXPECT_EQ(r.triangle_count, 64u);
}

TEST(CullBox, GiantTriangleCrossesEveryBox) {
  auto scene = lattice_scene(4, 2, {0, 0, 0});
  scene->source.add(test::make_memory_chunk(
      1000, {Tri{Vec3d{-1e4, -1e4, 0.01}, Vec3d{1e4, -1e4, 0.01}, Vec3d{0, 1e4, 0.01}}}));
  CullBoxParams params;
  params.triangle_budget = 64;
  params.min_half_size = 0.1;
  CullBoxResult r = find_cull_box({0, 0, 0}, params, scene->source);
  // The giant triangle is at distance 0.01 and always counts: 1 + 8 at 0.5, 1 + 64 at 1.5.
  EXPECT_NEAR(r.half_size, 1.5, 1e-9);
  EXPECT_EQ(r.triangle_count, 9u);
  params.triangle_budget = 0;
  params.min_half_size = 0.001;
  r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_NEAR(r.half_size, 0.01, 1e-9);
  EXPECT_EQ(r.triangle_count, 0u);
  params.min_half_size = 0.2;
  r = find_cull_box({0, 0, 0}, params, scene->source);
  EXPECT_EQ(r.half_size, 0.2);
  EXPECT_TRUE(r.budget_exceeded_at_min);
  EXPECT_EQ(r.triangle_count, 1u);
  ASSERT_EQ(r.near_field.size(), 1u);
  EXPECT_EQ(r.near_field[0].chunk_id, 1000);
  EXPECT_TRUE(r.near_field[0].whole);
}

TEST(CullBox, AllGeometryAtOnePoint) {
  test::MemoryChunkSource source;
  const Vec3d q{3, -2, 1};
  for (int c = 0; c < 4; ++c)
    source.add(test::make_memory_chunk(c + 1, std::vector<Tri>(500, Tri{q, q, q}), q));
  CullBoxParams params;
  params.triangle_budget = 100;
  params.min_half_size = 0.5;
  CullBoxResult r = find_cull_box({0, 0, 0}, params, source);
  EXPECT_NEAR(r.half_size, 3.0, 1e-9);
  EXPECT_LT(r.half_size, 3.0);
  EXPECT_EQ(r.triangle_count, 0u);
  // Centre on the point: everything is in the smallest box.
  r = find_cull_box(q, params, source);
  EXPECT_EQ(r.half_size, 0.5);
  EXPECT_TRUE(r.budget_exceeded_at_min);
  EXPECT_EQ(r.triangle_count, 2000u);
  EXPECT_EQ(r.near_field.size(), 4u);
  // Budget covering all of them: the model extent (0 from the point), floored at min.
  params.triangle_budget = 2000;
  r = find_cull_box(q, params, source);
  EXPECT_EQ(r.half_size, 0.5);
  EXPECT_FALSE(r.budget_exceeded_at_min);
}

TEST(CullBox, CentreFarOutsideTheModel) {
  auto scene = lattice_scene(4, 2, {0, 0, 0});
  const Vec3d c{1000, 5, -3};
  CullBoxParams params;
  params.triangle_budget = 64;
  params.min_half_size = 0.5;
  const CullBoxResult r = find_cull_box(c, params, scene->source);
  // Distances are 1000 - p.x for every lattice point (less the 1/1024 offset
  // corner on the +x side): planes of 64 triangles at 996.5, 997.5, ... minus
  // 1/1024; 64 fit, the second plane does not.
  EXPECT_NEAR(r.half_size, 997.5 - 1.0 / 1024, 1e-6);
  EXPECT_EQ(r.triangle_count, 64u);
  EXPECT_EQ(brute_count(scene->triangles, c, r.half_size), 64u);
}

// Random scenes of mixed triangles (including degenerate ones) chunked on a
// grid, checked against sorting every triangle's distance.
struct RandomScene {
  test::MemoryChunkSource source;
  std::vector<Tri> triangles;
  std::map<std::int64_t, std::vector<Tri>> chunks;
};

std::unique_ptr<RandomScene> random_scene(std::uint64_t seed, int count, double cell) {
  auto scene = std::make_unique<RandomScene>();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> cluster(0, 3);
  std::map<std::int64_t, std::vector<Tri>> generated;
  for (int i = 0; i < count; ++i) {
    Tri t = random_triangle(rng, 10, 0.3);
    if (i % 3 == 0)  // a dense cluster near (2, 2, 0)
      for (Vec3d& p : t) p = p * 0.1 + Vec3d{2 + cluster(rng) * 0.1, 2, 0};
    const Vec3d m = (t[0] + t[1] + t[2]) * (1.0 / 3);
    const auto key = [&](double v) { return static_cast<std::int64_t>(std::floor(v / cell)) + 1000; };
    generated[key(m.x) * 1000000 + key(m.y) * 1000 + key(m.z)].push_back(t);
  }
  // The brute-force reference reads the stored (float32-rounded) positions back.
  for (const auto& [id, tris] : generated) {
    scene->source.add(test::make_memory_chunk(id, tris, Vec3d{0.5, -0.25, 0.125}));
    const auto chunk = scene->source.load(id);
    for (std::size_t t = 0; t < chunk->triangle_count(); ++t) {
      const Tri stored{chunk->world(chunk->indices[3 * t]), chunk->world(chunk->indices[3 * t + 1]),
                       chunk->world(chunk->indices[3 * t + 2])};
      scene->triangles.push_back(stored);
      scene->chunks[id].push_back(stored);
    }
  }
  return scene;
}

TEST(CullBox, RandomScenesMatchBruteForce) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    auto scene = random_scene(seed, 6000, seed == 4 ? 20.0 : 2.5);
    std::mt19937_64 rng(seed * 101);
    std::uniform_real_distribution<double> pos(-12, 12);
    std::uniform_int_distribution<int> budget_pick(0, 6000);
    for (int trial = 0; trial < 12; ++trial) {
      const Vec3d c{pos(rng), pos(rng), pos(rng)};
      CullBoxParams params;
      params.triangle_budget = static_cast<std::uint64_t>(budget_pick(rng));
      params.min_half_size = 0.5;
      const CullBoxResult r = find_cull_box(c, params, scene->source);

      std::vector<double> d;
      for (const Tri& t : scene->triangles) d.push_back(triangle_linf_distance(c, t[0], t[1], t[2]));
      std::sort(d.begin(), d.end());
      const double extent = box_linf_reach(c, scene->source.model_bounds());
      double expected = std::max(extent, 0.5);
      if (params.triangle_budget < d.size() && d[params.triangle_budget] <= extent)
        expected = std::max(0.5, d[params.triangle_budget]);
      EXPECT_NEAR(r.half_size, expected, 1e-9) << "seed " << seed << " trial " << trial;
      const auto exact =
          static_cast<std::uint64_t>(std::upper_bound(d.begin(), d.end(), r.half_size) - d.begin());
      EXPECT_EQ(r.triangle_count, exact);
      EXPECT_EQ(r.budget_exceeded_at_min, exact > params.triangle_budget);
      if (!r.budget_exceeded_at_min) {
        EXPECT_LE(r.triangle_count, params.triangle_budget);
      }
      // The separating-axis test agrees, per chunk.
      for (const NearChunk& nc : r.near_field) {
        const auto& tris = scene->chunks.at(nc.chunk_id);
        EXPECT_EQ(nc.triangles, brute_count(tris, c, r.half_size));
        EXPECT_EQ(nc.whole, nc.triangles == tris.size());
      }
    }
  }
}

TEST(CullBox, ResultDoesNotDependOnChunkingAndIsDeterministic) {
  auto fine = random_scene(9, 5000, 1.0);
  auto coarse = random_scene(9, 5000, 8.0);
  CullBoxParams params;
  params.triangle_budget = 700;
  params.min_half_size = 0.25;
  for (const Vec3d& c : {Vec3d{0, 0, 0}, Vec3d{2, 2, 0}, Vec3d{-7, 3, 9}}) {
    const CullBoxResult a = find_cull_box(c, params, fine->source);
    const CullBoxResult b = find_cull_box(c, params, coarse->source);
    const CullBoxResult again = find_cull_box(c, params, fine->source);
    EXPECT_EQ(a.half_size, b.half_size);
    EXPECT_EQ(a.triangle_count, b.triangle_count);
    EXPECT_EQ(a.half_size, again.half_size);
    EXPECT_EQ(a.near_field, again.near_field);
    EXPECT_EQ(a.chunks_loaded, again.chunks_loaded);
  }
}

TEST(CullBox, LoadsOnlyTheChunksThatDecide) {
  auto scene = lattice_scene(16, 2, {0, 0, 0});  // 4096 chunks of 8 triangles
  CullBoxParams params;
  params.triangle_budget = 1000;
  params.min_half_size = 0.25;
  const CullBoxResult r = find_cull_box({0.3, -0.2, 0.1}, params, scene->source);
  EXPECT_EQ(r.triangle_count, brute_count(scene->triangles, {0.3, -0.2, 0.1}, r.half_size));
  EXPECT_LT(r.chunks_loaded, 600u);
  EXPECT_LT(r.chunks_queried, 4096u);
}

TEST(CullBox, RejectsBadParameters) {
  test::MemoryChunkSource source;
  CullBoxParams params;
  params.min_half_size = -1;
  EXPECT_THROW(find_cull_box({0, 0, 0}, params, source), std::invalid_argument);
  params.min_half_size = 2;
  params.max_half_size = 1;
  EXPECT_THROW(find_cull_box({0, 0, 0}, params, source), std::invalid_argument);
  params.max_half_size = 3;
  EXPECT_THROW(find_cull_box({std::nan(""), 0, 0}, params, source), std::invalid_argument);
}

TEST(CullBox, InconsistentChunkIsReportedByName) {
  test::MemoryChunkSource source;
  Chunk bad = test::make_memory_chunk(42, {Tri{Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}}});
  bad.indices[2] = 99;  // past the vertex array
  source.add(bad);
  CullBoxParams params;
  params.triangle_budget = 0;
  params.min_half_size = 0.1;
  try {
    find_cull_box({0.2, 0.2, 0.5}, params, source);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("chunk 42"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellbake
