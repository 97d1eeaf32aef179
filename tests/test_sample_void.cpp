// Tests for stages/sample_void: the void-surface objective on analytic box
// scenes (depth cube maps ray-cast exactly, tests/fixture_analytic_cube.h):
// rooms seen from inside (no void), open sky (no void), a half space with an
// exact answer of one half, a pillar's shadow against a brute-force
// reference that marches the true scene finely, and the contract's edge
// cases and errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "stages/sample/sample_void.h"
#include "tests/fixture_analytic_cube.h"

namespace cellbake {
namespace {

constexpr int kMapSize = 128;

std::vector<VoidSample> void_samples(const std::vector<CubeSample>& cubes) {
  std::vector<VoidSample> out;
  for (const CubeSample& c : cubes) out.push_back({&c});
  return out;
}

// Scene for the shadow tests: a wall at x = 10 and a full-height pillar in
// front of it, seen from the origin.
const std::vector<Box3d> kPillarScene{
    {{10, -20, -20}, {10.2, 20, 20}},  // wall
    {{4, -0.5, -20}, {5, 0.5, 20}},    // pillar
};

// Brute-force reference of the contract's idea without its discretisation:
// a ray is void when, before it meets the true scene, it passes a point that
// no sample's eye sees (the segment eye -> point meets a box first). Marched
// in steps of at most 0.01.
double reference_void_fraction(const Vec3d& candidate, const std::vector<Vec3d>& eyes,
                               const std::vector<Box3d>& boxes, const VoidParams& params,
                               double max_distance) {
  const int n = params.face_size;
  double void_weight = 0, total = 0;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis basis = cube_face_basis(f);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double s = 2 * (i + 0.5) / n - 1, t = 1 - 2 * (j + 0.5) / n;
        Vec3d d = cube_face_direction(basis, s, t);
        const double w = 1 / std::pow(1 + s * s + t * t, 1.5);
        total += w;
        d = d * (1 / length(d));
        const double end = std::min(test::ray_boxes(candidate, d, boxes), max_distance);
        const int steps = std::max(1, static_cast<int>(std::ceil((end - params.start_distance) / 0.01)));
        bool unseen = false;
        for (int k = 0; k <= steps && !unseen; ++k) {
          const double u = params.start_distance + (end - params.start_distance) * (1 - 1e-9) * k / steps;
          const Vec3d x = candidate + d * u;
          bool seen = false;
          for (const Vec3d& e : eyes) {
            const double dist = length(x - e);
            seen = seen || test::ray_boxes(e, (x - e) * (1 / dist), boxes) >= dist;
          }
          unseen = !seen;
        }
        if (unseen) void_weight += w;
      }
  }
  return void_weight / total;
}

TEST(VoidFraction, ClosedRoomSeenFromItsCentreHasNoVoid) {
  const std::vector<Box3d> room{{{-5, -5, -5}, {5, 5, 5}}};
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, room, kMapSize)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  const VoidParams params;
  // Every ray from inside stays in the sample's free space until it reaches a
  // wall the sample sees.
  for (const Vec3d& c :
       {Vec3d{0, 0, 0}, Vec3d{1, 2, -1}, Vec3d{3, 3, 3}, Vec3d{-4.5, 0.2, 0}, Vec3d{4.9, 4.9, -4.9}}) {
    const VoidResult r = void_fraction(c, samples, params);
    EXPECT_EQ(r.rays, 6u * params.face_size * params.face_size);
    EXPECT_EQ(r.void_rays, 0u) << c.x << " " << c.y << " " << c.z;
    EXPECT_EQ(r.fraction, 0.0);
  }
}

TEST(VoidFraction, OpenSkyHasNoVoid) {
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({1, 2, 3}, {}, 16)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  for (const Vec3d& c : {Vec3d{1, 2, 3}, Vec3d{0, 0, 0}, Vec3d{100, -50, 7}}) {
    const VoidResult r = void_fraction(c, samples, {});
    EXPECT_EQ(r.void_rays, 0u);
    EXPECT_EQ(r.fraction, 0.0);
  }
}

TEST(VoidFraction, CandidateInsideAnObjectIsAllVoid) {
  // Inside the pillar every ray starts behind the sample's surfaces; the
  // weights of all rays add up to the whole sphere.
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, kPillarScene, kMapSize)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  for (int face_size : {1, 4, 24}) {
    VoidParams params;
    params.face_size = face_size;
    const VoidResult r = void_fraction({4.5, 0, 0.3}, samples, params);
    EXPECT_EQ(r.rays, 6u * face_size * face_size);
    EXPECT_EQ(r.void_rays, r.rays);
    EXPECT_NEAR(r.fraction, 1.0, 1e-12);
  }
}

TEST(VoidFraction, HalfSpaceBelowAFloorIsHalfVoid) {
  // A floor (top at z = -1) seen from the origin; the candidate sits on it,
  // right below the sample. With no surface tolerance every downward ray
  // starts under the floor (void), every upward ray is free (seen): exactly
  // half of the sphere by the symmetry of the pixel weights.
  const std::vector<Box3d> floor{{{-1e4, -1e4, -2}, {1e4, 1e4, -1}}};
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, floor, kMapSize)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  VoidParams params;
  params.surface_tolerance = 0;
  const VoidResult r = void_fraction({0, 0, -1}, samples, params);
  EXPECT_EQ(r.void_rays * 2, r.rays);
  EXPECT_NEAR(r.fraction, 0.5, 1e-12);
  // With the default tolerance, a downward ray at angle a below the horizon
  // starts 0.05 sin(a) under the floor, on its surface while that is within
  // 3% of its depth 1 + 0.05 sin(a): seen for sin(a) <= 0.03 / 0.0485. Void
  // are the rays steeper than that, (1 - 0.03 / 0.0485) / 2 of the sphere;
  // the 24^2-per-face rays resolve that cone's rim to well within 0.01.
  const VoidResult tolerant = void_fraction({0, 0, -1}, samples, {});
  EXPECT_NEAR(tolerant.fraction, (1 - 0.03 / 0.0485) / 2, 0.01);
}

TEST(VoidFraction, PillarShadowMatchesBruteForce) {
  const Vec3d eye{0, 0, 0};
  const std::vector<CubeSample> cubes{test::analytic_cube_sample(eye, kPillarScene, kMapSize)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  const VoidParams params;
  for (const Vec3d& c : {Vec3d{0, 3, 0}, Vec3d{2, -2, 1}, Vec3d{7, 4, 0}}) {
    const VoidResult r = void_fraction(c, samples, params);
    const double max_distance = length(c - eye) + 2 * 20.2;  // as void_fraction's default
    const double want = reference_void_fraction(c, {eye}, kPillarScene, params, max_distance);
    EXPECT_GT(r.fraction, 0.0) << c.x << " " << c.y << " " << c.z;
    // Rays can differ only along the outline of the shadow as seen from the
    // candidate (pixel quantisation of the 128^2 map and of the steps) and
    // where the 3% surface tolerance calls a ray that enters the shadow right
    // in front of the wall seen: within 10% of the answer plus 5 rays (each
    // ray is about 1/3456 of the sphere; the measured gaps are 1-5%).
    EXPECT_NEAR(r.fraction, want, 0.1 * want + 5.0 / r.rays) << c.x << " " << c.y << " " << c.z;
  }
}

TEST(VoidFraction, SampleAtTheCandidateRemovesTheVoid) {
  const Vec3d candidate{0, 3, 0};
  const std::vector<CubeSample> one{test::analytic_cube_sample({0, 0, 0}, kPillarScene, kMapSize)};
  const double before = void_fraction(candidate, void_samples(one), {}).fraction;
  EXPECT_GT(before, 0.005);
  std::vector<CubeSample> two = one;
  two.push_back(test::analytic_cube_sample(candidate, kPillarScene, kMapSize));
  const VoidResult after = void_fraction(candidate, void_samples(two), {});
  // A sample at the candidate certifies every point of every ray up to the
  // surface the ray meets, so no ray can be void; allow two rays for pixel
  // quantisation at silhouettes (each ray is about 1/3456 of the sphere).
  EXPECT_LE(after.void_rays, 2u);
  EXPECT_LT(after.fraction, 2.0 / after.rays * 1.5);
}

TEST(VoidFraction, CandidateAtTheSampleHasNoVoid) {
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, kPillarScene, kMapSize)};
  const VoidResult r = void_fraction({0, 0, 0}, void_samples(cubes), {});
  EXPECT_EQ(r.void_rays, 0u);
  EXPECT_EQ(r.fraction, 0.0);
}

TEST(VoidFraction, IndependentOfSampleOrderAndDeterministic) {
  const std::vector<Box3d> scene{{{-10, -10, -1}, {10, 10, 4}},  // room
                                 {{-3, -1, -1}, {-2, 1, 4}},
                                 {{2, -4, -1}, {3, -1, 2}},
                                 {{1, 3, 1}, {5, 4, 2}}};
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({-6, 0, 1.5}, scene, kMapSize),
                                      test::analytic_cube_sample({6, 6, 1.5}, scene, kMapSize),
                                      test::analytic_cube_sample({0, -7, 0.5}, scene, kMapSize)};
  const std::vector<CubeSample> reversed(cubes.rbegin(), cubes.rend());
  for (const Vec3d& c : {Vec3d{-8, 6, 1.5}, Vec3d{4, -6, 0.7}, Vec3d{-1, 5, 2.5}}) {
    const VoidResult a = void_fraction(c, void_samples(cubes), {});
    const VoidResult b = void_fraction(c, void_samples(cubes), {});
    const VoidResult r = void_fraction(c, void_samples(reversed), {});
    EXPECT_EQ(a.void_rays, b.void_rays);
    EXPECT_EQ(a.fraction, b.fraction);
    EXPECT_EQ(a.void_rays, r.void_rays);
    EXPECT_GE(a.fraction, 0.0);
    EXPECT_LE(a.fraction, 1.0);
  }
}

// Best next view scores the same candidates again after each new sample: a
// memory carried from call to call gives the fresh result bit for bit while
// marching only the rays not already seen for good.
TEST(VoidFraction, RayMemoryGivesTheFreshResultWithFewerRaysMarched) {
  const std::vector<Box3d> boxes{{{-3, -1, -1}, {-2, 1, 4}},
                                 {{2, -4, -1}, {3, -1, 2}},
                                 {{1, 3, 1}, {5, 4, 2}},
                                 {{-6, -7, -1}, {-5, -3, 3}}};
  std::vector<Box3d> room = boxes, yard = boxes;  // closed, and open to the sky (rule 4's shortcut)
  room.push_back({{-10, -10, -1}, {10, 10, 4}});
  yard.push_back({{-30, -30, -1.2}, {30, 30, -1}});
  const std::vector<Vec3d> eyes{{-6, 0, 1.5}, {6, 6, 1.5}, {0, -7, 0.5}, {-8, 6, 1.5}, {4, -6, 0.7}};
  for (const std::vector<Box3d>* scene : {&room, &yard}) {
    std::vector<CubeSample> cubes;
    for (const Vec3d& e : eyes) cubes.push_back(test::analytic_cube_sample(e, *scene, kMapSize));
    for (const double max_distance : {0.0, 40.0}) {  // 0: the march's end grows with the samples
      VoidParams params;
      params.max_distance = max_distance;
      for (const Vec3d& c : {Vec3d{-1, 5, 2.5}, Vec3d{7, -2, 1}, Vec3d{-4, -4, 0.3}}) {
        VoidRayMemory memory;
        std::size_t marched = 0, rays = 0;
        for (std::size_t k = 1; k <= cubes.size(); ++k) {
          const std::vector<CubeSample> first(cubes.begin(), cubes.begin() + std::ptrdiff_t(k));
          const VoidResult fresh = void_fraction(c, void_samples(first), params);
          const VoidResult remembered = void_fraction(c, void_samples(first), params, memory);
          EXPECT_EQ(remembered.fraction, fresh.fraction) << c.x << " " << c.y << " with " << k << " samples";
          EXPECT_EQ(remembered.void_rays, fresh.void_rays);
          EXPECT_EQ(remembered.rays, fresh.rays);
          EXPECT_EQ(fresh.marched_rays, fresh.rays);
          if (k > 1) marched += remembered.marched_rays, rays += remembered.rays;
        }
        // Most rays meet a wall or the sky and are not marched again.
        if (max_distance > 0) EXPECT_LT(marched, rays / 3) << c.x << " " << c.y;
      }
    }
  }
}

TEST(VoidFraction, RayMemoryOfAnotherCandidateParamsOrSamplesThrows) {
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, kPillarScene, 32),
                                      test::analytic_cube_sample({0, 3, 0}, kPillarScene, 32)};
  const std::vector<CubeSample> other{test::analytic_cube_sample({1, 0, 0}, kPillarScene, 32)};
  VoidParams params;
  params.face_size = 8;
  VoidRayMemory memory;
  void_fraction({2, 1, 0}, void_samples({cubes[0]}), params, memory);
  EXPECT_THROW(void_fraction({2, 1.5, 0}, void_samples(cubes), params, memory), std::invalid_argument);
  EXPECT_THROW(void_fraction({2, 1, 0}, void_samples(other), params, memory), std::invalid_argument);
  EXPECT_THROW(void_fraction({2, 1, 0}, std::vector<VoidSample>{}, params, memory), std::invalid_argument);
  VoidParams finer = params;
  finer.face_size = 12;
  EXPECT_THROW(void_fraction({2, 1, 0}, void_samples(cubes), finer, memory), std::invalid_argument);
  VoidParams looser = params;
  looser.surface_tolerance = 0.05;
  EXPECT_THROW(void_fraction({2, 1, 0}, void_samples(cubes), looser, memory), std::invalid_argument);
  EXPECT_NO_THROW(void_fraction({2, 1, 0}, void_samples(cubes), params, memory));
  EXPECT_EQ(memory.eyes.size(), 2u);
}

TEST(VoidFraction, BadInputThrows) {
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, kPillarScene, 8)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(void_fraction({0, 1, 0}, {}, {}), std::invalid_argument);
  EXPECT_THROW(void_fraction({nan, 1, 0}, samples, {}), std::invalid_argument);
  EXPECT_THROW(void_fraction({inf, 1, 0}, samples, {}), std::invalid_argument);
  const std::vector<VoidSample> null_cube{{nullptr}};
  EXPECT_THROW(void_fraction({0, 1, 0}, null_cube, {}), std::invalid_argument);

  CubeSample uneven = cubes[0];
  uneven.faces[3] = test::analytic_cube_sample({0, 0, 0}, kPillarScene, 4).faces[3];
  const std::vector<VoidSample> uneven_samples{{&uneven}};
  EXPECT_THROW(void_fraction({0, 1, 0}, uneven_samples, {}), std::invalid_argument);
  CubeSample short_depth = cubes[0];
  short_depth.faces[2].depth.pop_back();
  const std::vector<VoidSample> short_samples{{&short_depth}};
  EXPECT_THROW(void_fraction({0, 1, 0}, short_samples, {}), std::invalid_argument);
  CubeSample bad_eye = cubes[0];
  bad_eye.eye.y = nan;
  const std::vector<VoidSample> bad_eye_samples{{&bad_eye}};
  EXPECT_THROW(void_fraction({0, 1, 0}, bad_eye_samples, {}), std::invalid_argument);

  auto with = [](auto change) {
    VoidParams p;
    change(p);
    return p;
  };
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([](VoidParams& p) { p.face_size = 0; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([](VoidParams& p) { p.step_ratio = 0; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([&](VoidParams& p) { p.step_ratio = nan; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([](VoidParams& p) { p.start_distance = 0; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([](VoidParams& p) { p.max_distance = -1; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([&](VoidParams& p) { p.max_distance = inf; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([](VoidParams& p) { p.surface_tolerance = -0.1; })),
               std::invalid_argument);
  EXPECT_THROW(void_fraction({0, 1, 0}, samples, with([&](VoidParams& p) { p.jump = nan; })),
               std::invalid_argument);
}

TEST(VoidFraction, MaxDistanceEndsRaysIntoTheUnknown) {
  // Rays stop (seen) at max_distance: a short one ends every ray before the
  // pillar's shadow; a long one lets rays that pass the wall's edges reach
  // the wall's own shadow (unknown space behind it) beyond the default
  // distance (|candidate - eye| + 2 * largest depth, about 43), so the
  // fraction grows.
  const std::vector<CubeSample> cubes{test::analytic_cube_sample({0, 0, 0}, kPillarScene, kMapSize)};
  const std::vector<VoidSample> samples = void_samples(cubes);
  VoidParams params;
  const VoidResult by_default = void_fraction({0, 3, 0}, samples, params);
  params.max_distance = 1;
  EXPECT_EQ(void_fraction({0, 3, 0}, samples, params).fraction, 0.0);
  params.max_distance = 200;
  EXPECT_GT(void_fraction({0, 3, 0}, samples, params).void_rays, by_default.void_rays);
}

}  // namespace
}  // namespace cellbake
