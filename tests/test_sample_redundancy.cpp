// Redundant-pixel removal for delta scans and the background colour fill, on
// analytic box scenes with known answers.
#include <gtest/gtest.h>

#include "stages/background_fill.h"
#include "stages/sample_redundancy.h"
#include "tests/fixture_analytic_cube.h"

namespace cellbake {
namespace {

using test::ColoredBox;

// A closed room 20 x 20 x 6 m (walls 0.2 m thick) with a pillar in it.
std::vector<ColoredBox> room_with_pillar() {
  return {{{{-10, -10, -0.2}, {10, 10, 0}}, {90, 90, 90, 255}},     // floor
          {{{-10, -10, 6}, {10, 10, 6.2}}, {120, 120, 140, 255}},   // ceiling
          {{{-10.2, -10, 0}, {-10, 10, 6}}, {200, 60, 60, 255}},    // walls
          {{{10, -10, 0}, {10.2, 10, 6}}, {60, 200, 60, 255}},
          {{{-10, -10.2, 0}, {10, -10, 6}}, {60, 60, 200, 255}},
          {{{-10, 10, 0}, {10, 10.2, 6}}, {200, 200, 60, 255}},
          {{{4, -0.5, 0}, {5, 0.5, 6}}, {250, 250, 250, 255}}};     // pillar
}

// Calls visit(face, pixel index, world point, kept) for every covered pixel of
// `original`, kept = still covered in `reduced`.
template <class Visit>
void for_each_covered_pixel(const CubeSample& original, const CubeSample& reduced, Visit visit) {
  const int n = original.faces[0].size;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis b = cube_face_basis(f);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::size_t k = std::size_t(j) * n + i;
        const float depth = original.faces[f].depth[k];
        if (!std::isfinite(depth)) continue;
        const Vec3d dir = cube_face_direction(b, 2 * (i + 0.5) / n - 1, 1 - 2 * (j + 0.5) / n);
        visit(f, k, original.eye + dir * double(depth), std::isfinite(reduced.faces[f].depth[k]));
      }
  }
}

std::size_t covered(const CubeSample& s) {
  std::size_t n = 0;
  for (const CubeFace& f : s.faces)
    for (float d : f.depth) n += std::isfinite(d) ? 1 : 0;
  return n;
}

TEST(SampleRedundancy, ASampleAtTheSameEyeIsWhollyRedundant) {
  const auto scene = room_with_pillar();
  const CubeSample a = test::analytic_colored_cube_sample({0, 0, 1.7}, scene, 64);
  CubeSample d = a;
  const CubeSample* ancestors[] = {&a};
  const RedundancyStats st = remove_redundant_pixels(d, ancestors);
  EXPECT_EQ(st.covered, covered(a));
  EXPECT_EQ(st.removed, st.covered);
  EXPECT_EQ(covered(d), 0u);
}

TEST(SampleRedundancy, ADeltaScanKeepsOnlyWhatThePillarHidFromItsParent) {
  const auto scene = room_with_pillar();
  const int n = 128;
  const CubeSample a = test::analytic_colored_cube_sample({0, 0, 1.7}, scene, n);
  const CubeSample original = test::analytic_colored_cube_sample({1.5, 1.5, 1.7}, scene, n);
  CubeSample d = original;
  const CubeSample* ancestors[] = {&a};
  RedundancyParams p;
  p.keep_margin = 0;
  const RedundancyStats st = remove_redundant_pixels(d, ancestors, p);
  ASSERT_GT(st.covered, 0u);
  // The pillar hides a small part of the room: most of the delta is redundant.
  EXPECT_GT(double(st.removed) / double(st.covered), 0.9);
  EXPECT_LT(st.removed, st.covered);
  // Every point hidden from the parent by the pillar is kept (a pillar shrunk
  // by about 1.5 of the parent's pixels at its distance: within a pixel of its
  // silhouette the parent's own surfaces still reach); every kept point is one
  // the parent does not hold (by the stage's own rule).
  Box3d core = scene.back().box;
  for (int axis = 0; axis < 3; ++axis) core.lo[axis] += 0.1, core.hi[axis] -= 0.1;
  std::size_t hidden = 0;
  for_each_covered_pixel(original, d, [&](int f, std::size_t k, const Vec3d& point, bool kept) {
    if (kept) {
      EXPECT_FALSE(sample_holds_point(a, point, p));
    }
    const double t = test::ray_box_surface(a.eye, point - a.eye, core);
    const bool on_pillar = point.x >= 4 - 1e-9 && point.x <= 5 + 1e-9 && std::abs(point.y) <= 0.5 + 1e-9;
    if (t < 1.0 - 1e-3 && !on_pillar) {
      ++hidden;
      EXPECT_TRUE(kept) << "face " << f << " pixel " << k;
    }
  });
  EXPECT_GT(hidden, 0u);
}

TEST(SampleRedundancy, TwoSurfacesAFewMillimetresApartFarAwayAreToldApart) {
  // A 5 mm sheet 15-25 m away in the plane z = 0, seen from 2 m above by the
  // parent and from 2 m below by the delta (the two sides of a 4 m cell), at
  // 4.6 to 7.6 degrees: the underside is new to the delta, and along the
  // delta's rays it lies only 0.2-0.3 % behind the parent's top face. (The
  // sheet's 5 mm end faces are seen by both and may go.)
  const std::vector<ColoredBox> scene = {{{{15, -5, -0.0025}, {25, 5, 0.0025}}, {200, 100, 50, 255}}};
  const int n = 256;
  const CubeSample a = test::analytic_colored_cube_sample({0, 0, 2}, scene, n);
  const CubeSample original = test::analytic_colored_cube_sample({0, 0, -2}, scene, n);
  CubeSample d = original;
  const CubeSample* ancestors[] = {&a};
  // With the default one-ring margin (without it, the first and last rows of
  // the strip, where the parent's surface is extrapolated past its last
  // pixel, may go).
  remove_redundant_pixels(d, ancestors);
  std::size_t underside = 0, underside_removed = 0;
  for_each_covered_pixel(original, d, [&](int f, std::size_t k, const Vec3d& p, bool kept) {
    if (std::abs(p.z + 0.0025) > 1e-6) return;
    ++underside;
    underside_removed += kept ? 0 : 1;
    // Away from the sheet's side edges, none may go.
    if (std::abs(p.y) < 4.5) {
      EXPECT_TRUE(kept) << "face " << f << " pixel " << k;
    }
  });
  EXPECT_GT(underside, 300u);
  // At the sheet's corners, where the parent's strip ends in both directions
  // within a pixel, a few may (measured: 3 of 472).
  EXPECT_LE(underside_removed, underside / 100) << "of " << underside;
}

TEST(SampleRedundancy, KeepMarginGrowsKeptPixelsBackOverTheSeam) {
  const auto scene = room_with_pillar();
  const CubeSample a = test::analytic_colored_cube_sample({0, 0, 1.7}, scene, 96);
  CubeSample tight = test::analytic_colored_cube_sample({1.5, 1.5, 1.7}, scene, 96), grown = tight;
  const CubeSample* ancestors[] = {&a};
  RedundancyParams p;
  p.keep_margin = 0;
  const auto st0 = remove_redundant_pixels(tight, ancestors, p);
  p.keep_margin = 2;
  const auto st2 = remove_redundant_pixels(grown, ancestors, p);
  EXPECT_LT(st2.removed, st0.removed);
  // Everything kept without a margin is kept with one.
  for (int f = 0; f < kCubeFaces; ++f)
    for (std::size_t k = 0; k < tight.faces[f].depth.size(); ++k)
      if (std::isfinite(tight.faces[f].depth[k])) {
        EXPECT_TRUE(std::isfinite(grown.faces[f].depth[k]));
      }
}

TEST(SampleRedundancy, RejectsMismatchedSizes) {
  const auto scene = room_with_pillar();
  const CubeSample a = test::analytic_colored_cube_sample({0, 0, 1.7}, scene, 32);
  CubeSample d = test::analytic_colored_cube_sample({1, 0, 1.7}, scene, 16);
  const CubeSample* ancestors[] = {&a};
  EXPECT_THROW(remove_redundant_pixels(d, ancestors), std::invalid_argument);
}

TEST(BackgroundFill, BackgroundTakesNearbyColoursAndCoveredPixelsStay) {
  CubeFace f;
  f.size = 8;
  f.color.assign(64, Rgba8{0, 0, 0, 0});
  f.depth.assign(64, kBackgroundDepth);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 4; ++i) {
      f.depth[j * 8 + i] = 5;
      f.color[j * 8 + i] = Rgba8{200, 100, 50, 255};
    }
  CubeFace filled = f;
  fill_background_colors(filled);
  for (int k = 0; k < 64; ++k) {
    if (std::isfinite(f.depth[k])) {
      EXPECT_EQ(filled.color[k], f.color[k]);
    } else {
      EXPECT_EQ(filled.color[k], (Rgba8{200, 100, 50, 0}));  // one colour nearby: extended exactly, alpha 0
    }
  }
  CubeFace empty;
  empty.size = 4;
  empty.color.assign(16, Rgba8{0, 0, 0, 0});
  empty.depth.assign(16, kBackgroundDepth);
  fill_background_colors(empty);
  EXPECT_EQ(empty.color[5], (Rgba8{0, 0, 0, 0}));
}

}  // namespace
}  // namespace cellbake
