// Redundant-pixel removal for delta scans and the background colour fill, on
// analytic box scenes with known answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "stages/background_fill.h"
#include "stages/sample/sample_redundancy.h"
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
  // Exactly: two rings, each keeping every removed pixel with a kept one among its 8 neighbours.
  const CubeSample original = test::analytic_colored_cube_sample({1.5, 1.5, 1.7}, scene, 96);
  const int n = 96;
  for (int f = 0; f < kCubeFaces; ++f) {
    std::vector<int> state(std::size_t(n) * n);  // 0 background, 1 kept, 2 removed
    for (std::size_t k = 0; k < state.size(); ++k)
      state[k] = !std::isfinite(original.faces[f].depth[k]) ? 0
                 : std::isfinite(tight.faces[f].depth[k])   ? 1
                                                            : 2;
    for (int ring = 0; ring < 2; ++ring) {
      std::vector<int> next = state;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int ii = i + di, jj = j + dj;
              if (state[std::size_t(j) * n + i] == 2 && ii >= 0 && jj >= 0 && ii < n && jj < n &&
                  state[std::size_t(jj) * n + ii] == 1)
                next[std::size_t(j) * n + i] = 1;
            }
      state = next;
    }
    for (std::size_t k = 0; k < state.size(); ++k)
      ASSERT_EQ(state[k] == 1, std::isfinite(grown.faces[f].depth[k])) << "face " << f << " pixel " << k;
  }
}

// The one-surface rule written out plainly (every second difference taken,
// then compared), for points whose 2x2 neighbourhood holds one surface; null
// for the others (a depth jump: another rule).
std::optional<bool> one_surface_rule(const CubeSample& a, const Vec3d& point, const RedundancyParams& prm) {
  const int n = a.faces[0].size;
  const Vec3d v = point - a.eye;
  const double ax = std::abs(v.x), ay = std::abs(v.y), az = std::abs(v.z);
  const int face = ax >= ay && ax >= az ? (v.x >= 0 ? 0 : 1)
                   : ay >= az           ? (v.y >= 0 ? 2 : 3)
                                        : (v.z >= 0 ? 4 : 5);
  const FaceBasis b = cube_face_basis(face);
  const double depth = dot(v, b.forward);
  if (!(depth > 0)) return std::nullopt;
  const double x = std::clamp((dot(v, b.right) / depth + 1) * 0.5 * n - 0.5, 0.0, n - 1.0);
  const double y = std::clamp((1 - dot(v, b.up) / depth) * 0.5 * n - 0.5, 0.0, n - 1.0);
  const CubeFace& f = a.faces[std::size_t(face)];
  const auto inv = [&](int i, int j) {
    const float d = f.depth[std::size_t(j) * n + i];
    return std::isfinite(d) ? 1.0 / d : 0.0;
  };
  const int i0 = std::min(int(x), n - 2), j0 = std::min(int(y), n - 2), i1 = i0 + 1, j1 = j0 + 1;
  const double fx = x - i0, fy = y - j0, w = 1.0 / depth;
  const double w00 = inv(i0, j0), w10 = inv(i1, j0), w01 = inv(i0, j1), w11 = inv(i1, j1);
  const double lo = std::min({w00, w10, w01, w11}), hi = std::max({w00, w10, w01, w11});
  if (!(lo > 0 && hi <= lo * (1 + prm.jump))) return std::nullopt;
  const double interpolated = (w00 * (1 - fx) + w10 * fx) * (1 - fy) + (w01 * (1 - fx) + w11 * fx) * fy;
  double curvature = std::abs(w00 + w11 - w10 - w01);
  const auto second = [&](int ia, int ja, int ib, int jb, int ic, int jc) {
    if (ia < 0 || ja < 0 || ic >= n || jc >= n) return;
    const double a0 = inv(ia, ja), b0 = inv(ib, jb), c0 = inv(ic, jc);
    if (a0 <= 0 || c0 <= 0 || std::max(a0, c0) > std::min(a0, c0) * (1 + prm.jump)) return;
    curvature = std::max(curvature, std::abs(a0 - 2 * b0 + c0));
  };
  for (int j : {j0, j1}) second(i0 - 1, j, i0, j, i1, j), second(i0, j, i1, j, i1 + 1, j);
  for (int i : {i0, i1}) second(i, j0 - 1, i, j0, i, j1), second(i, j0, i, j1, i, j1 + 1);
  return std::abs(interpolated - w) <= prm.tolerance * w + 0.5 * curvature;
}

// sample_holds_point stops reading neighbours once the allowance covers the
// miss: on a curved, stepped surface with holes it answers as the plain rule.
TEST(SampleRedundancy, HeldPointsAnswerAsTheRuleWithEverySecondDifference) {
  constexpr int n = 24;
  CubeSample a;
  a.eye = {0.3, -0.2, 0.1};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int f = 0; f < kCubeFaces; ++f) {
    CubeFace& face = a.faces[std::size_t(f)];
    face.size = n;
    face.depth.resize(std::size_t(n) * n);
    face.color.assign(face.depth.size(), Rgba8{});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double d = 5 + 0.8 * std::sin(0.9 * i + f) * std::cos(0.5 * j) + 0.02 * unit(rng);
        if (i > 15) d *= 1.3;  // a step
        face.depth[std::size_t(j) * n + i] = unit(rng) < 0.03 ? kBackgroundDepth : float(d);
      }
  }
  const RedundancyParams prm;
  std::size_t compared = 0, held = 0;
  for (int k = 0; k < 40000; ++k) {
    const int f = int(unit(rng) * kCubeFaces) % kCubeFaces;
    const FaceBasis b = cube_face_basis(f);
    const double s = 2 * unit(rng) - 1, t = 2 * unit(rng) - 1;
    const double col = (s + 1) * 0.5 * n - 0.5, row = (1 - t) * 0.5 * n - 0.5;
    const int i = std::clamp(int(std::lround(col)), 0, n - 1),
              j = std::clamp(int(std::lround(row)), 0, n - 1);
    const float stored = a.faces[std::size_t(f)].depth[std::size_t(j) * n + i];
    if (!std::isfinite(stored)) continue;
    // Depths from on the surface to a few per cent off it, most within the allowance's scale.
    const double off = (unit(rng) - 0.5) * (k % 3 == 0 ? 0.05 : 2e-3);
    const Vec3d point = a.eye + cube_face_direction(b, s, t) * (double(stored) * (1 + off));
    const std::optional<bool> want = one_surface_rule(a, point, prm);
    if (!want) continue;
    EXPECT_EQ(sample_holds_point(a, point, prm), *want) << "face " << f << " s " << s << " t " << t;
    ++compared;
    held += *want ? 1 : 0;
  }
  EXPECT_GT(compared, 20000u);
  EXPECT_GT(held, compared / 10);
  EXPECT_LT(held, compared - compared / 10);
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
