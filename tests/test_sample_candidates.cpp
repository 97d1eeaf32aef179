// Tests for stages/sample_candidates: Voronoi best-next-view candidates on
// hand-made configurations with exact answers, the special cases of the
// contract, and random configurations against a brute-force Voronoi reference
// (circumcentres with empty circles, bisector crossings whose pair is nearest).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "stages/sample/sample_candidates.h"

namespace cellbake {
namespace {

const Rect2d kUnit{{0, 0}, {1, 1}};

void expect_points(const std::vector<Vec2d>& got, const std::vector<Vec2d>& want, double tol = 1e-12) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_NEAR(got[i].x, want[i].x, tol) << "point " << i;
    EXPECT_NEAR(got[i].y, want[i].y, tol) << "point " << i;
  }
}

// Every point of a has a point of b within tol.
bool covered(const std::vector<Vec2d>& a, const std::vector<Vec2d>& b, double tol) {
  for (const Vec2d& p : a) {
    bool found = false;
    for (const Vec2d& q : b) found = found || std::hypot(p.x - q.x, p.y - q.y) < tol;
    if (!found) return false;
  }
  return true;
}

bool sorted_unique(const std::vector<Vec2d>& v) {
  for (std::size_t i = 1; i < v.size(); ++i)
    if (!(v[i - 1].x < v[i].x || (v[i - 1].x == v[i].x && v[i - 1].y < v[i].y))) return false;
  return true;
}

TEST(VoronoiCandidates, NoSamplesGivesTheCentre) {
  expect_points(voronoi_candidates({}, {{1, 2}, {5, 4}}), {{3, 3}});
}

TEST(VoronoiCandidates, OneSampleGivesTheCorners) {
  expect_points(voronoi_candidates({{0.3, 0.6}}, kUnit), {{0, 0}, {0, 1}, {1, 0}, {1, 1}});
  // A corner that is the sample itself is dropped.
  expect_points(voronoi_candidates({{1, 1}}, kUnit), {{0, 0}, {0, 1}, {1, 0}});
}

TEST(VoronoiCandidates, TwoSamplesGiveTheBisectorEnds) {
  // Bisector of (0.2, 0.3) and (0.6, 0.5): through (0.4, 0.4) along (-1, 2);
  // it meets y = 0 at x = 0.6 and y = 1 at x = 0.1, and misses x = 0 and x = 1.
  expect_points(voronoi_candidates({{0.2, 0.3}, {0.6, 0.5}}, kUnit), {{0.1, 1}, {0.6, 0}});
}

TEST(VoronoiCandidates, ThreeSamplesGiveCircumcentreAndThreeRays) {
  // Circumcentre of (0.25, 0.25), (0.75, 0.25), (0.5, 0.75) is (0.5, 0.4375);
  // the rays leave it downwards along x = 0.5 and along (+-2, 1), meeting the
  // sides x = 0 and x = 1 after 0.25 of that vector, at y = 0.6875.
  expect_points(voronoi_candidates({{0.25, 0.25}, {0.75, 0.25}, {0.5, 0.75}}, kUnit),
                {{0, 0.6875}, {0.5, 0}, {0.5, 0.4375}, {1, 0.6875}});
}

TEST(VoronoiCandidates, CornersAndCentreGiveTheEdgeMidpointsOnce) {
  // The four Voronoi vertices lie on the boundary, and each is also the source
  // of a ray and the end of two diamond edges: reported once each.
  const std::vector<Vec2d> got = voronoi_candidates({{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}}, kUnit);
  expect_points(got, {{0, 0.5}, {0.5, 0}, {0.5, 1}, {1, 0.5}});
  EXPECT_TRUE(sorted_unique(got));
}

TEST(VoronoiCandidates, CollinearSamplesGiveParallelBisectors) {
  // Bisectors x + y = 0.4 and x + y = 1.2; no Voronoi vertices.
  const std::vector<Vec2d> want{{0, 0.4}, {0.2, 1}, {0.4, 0}, {1, 0.2}};
  expect_points(voronoi_candidates({{0.1, 0.1}, {0.3, 0.3}, {0.9, 0.9}}, kUnit), want);
  expect_points(voronoi_candidates({{0.9, 0.9}, {0.1, 0.1}, {0.3, 0.3}}, kUnit), want);
  // A vertical line of samples: horizontal bisectors.
  expect_points(voronoi_candidates({{0.5, 0.9}, {0.5, 0.1}, {0.5, 0.5}}, kUnit),
                {{0, 0.3}, {0, 0.7}, {1, 0.3}, {1, 0.7}});
}

TEST(VoronoiCandidates, DuplicateSamplesCountOnce) {
  expect_points(voronoi_candidates({{0.2, 0.3}, {0.6, 0.5}, {0.2, 0.3}, {0.6, 0.5}, {0.6, 0.5}}, kUnit),
                {{0.1, 1}, {0.6, 0}});
  // Closer than 1e-9 * (diagonal + 1) counts as the same sample.
  expect_points(voronoi_candidates({{0.2, 0.3}, {0.6, 0.5}, {0.2 + 1e-12, 0.3}}, kUnit),
                {{0.1, 1}, {0.6, 0}});
  // One distinct sample, several times: the corners.
  expect_points(voronoi_candidates({{0.3, 0.6}, {0.3, 0.6}, {0.3, 0.6}}, kUnit),
                {{0, 0}, {0, 1}, {1, 0}, {1, 1}});
  expect_points(
      voronoi_candidates({{0.25, 0.25}, {0.75, 0.25}, {0.5, 0.75}, {0.5, 0.75}, {0.25, 0.25}}, kUnit),
      {{0, 0.6875}, {0.5, 0}, {0.5, 0.4375}, {1, 0.6875}});
}

TEST(VoronoiCandidates, SegmentRect) {
  const Rect2d segment{{0, 0.5}, {1, 0.5}};
  // Two samples on the segment: their midpoint plus the end points.
  expect_points(voronoi_candidates({{0.25, 0.5}, {0.75, 0.5}}, segment), {{0, 0.5}, {0.5, 0.5}, {1, 0.5}});
  // Circumcentre of (0.2, 0.2), (0.8, 0.2), (0.5, 0.9) is (0.5, 17/35), just
  // below the segment; the two upper rays leave it along (+-0.7, 0.3) and
  // cross y = 0.5 after u = 1/21, at x = 0.5 +- 1/30.
  expect_points(voronoi_candidates({{0.2, 0.2}, {0.8, 0.2}, {0.5, 0.9}}, segment),
                {{0, 0.5}, {0.5 - 1.0 / 30, 0.5}, {0.5 + 1.0 / 30, 0.5}, {1, 0.5}});
  // One sample: the two ends; an end on the sample is dropped.
  expect_points(voronoi_candidates({{0.3, 0.2}}, segment), {{0, 0.5}, {1, 0.5}});
  expect_points(voronoi_candidates({{1, 0.5}}, segment), {{0, 0.5}});
  // A vertical segment.
  expect_points(voronoi_candidates({{0, 0}, {1, 1}}, {{0.5, 0}, {0.5, 1}}), {{0.5, 0}, {0.5, 0.5}, {0.5, 1}});
}

TEST(VoronoiCandidates, PointRect) {
  const Rect2d point{{0.3, 0.3}, {0.3, 0.3}};
  expect_points(voronoi_candidates({{0, 0}, {1, 0}, {0, 1}}, point), {{0.3, 0.3}});
  expect_points(voronoi_candidates({{0, 0}}, point), {{0.3, 0.3}});
  EXPECT_TRUE(voronoi_candidates({{0, 0}, {0.3, 0.3}}, point).empty());
}

TEST(VoronoiCandidates, SamplesOutsideTheRect) {
  // Two samples left and right of the square, symmetric about x = 0.5.
  expect_points(voronoi_candidates({{-3, 0.5}, {4, 0.5}}, kUnit), {{0.5, 0}, {0.5, 1}});
  // A bisector along a side (x = 0) gives that side's corners.
  expect_points(voronoi_candidates({{-1, 0.5}, {1, 0.5}}, kUnit), {{0, 0}, {0, 1}});
}

TEST(VoronoiCandidates, NonFiniteInputThrows) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(voronoi_candidates({{0, 0}, {nan, 1}}, kUnit), std::invalid_argument);
  EXPECT_THROW(voronoi_candidates({{inf, 0}}, kUnit), std::invalid_argument);
  EXPECT_THROW(voronoi_candidates({{0, 0}}, {{0, 0}, {inf, 1}}), std::invalid_argument);
  EXPECT_THROW(voronoi_candidates({{0, 0}}, {{nan, 0}, {1, 1}}), std::invalid_argument);
  EXPECT_THROW(voronoi_candidates({{0, 0}}, {{1, 0}, {0, 1}}), std::invalid_argument);  // lo > hi
}

// Brute-force reference: Voronoi vertices are circumcentres of triples whose
// circle holds no other sample; a boundary point is on a Voronoi edge when its
// two nearest samples are equally near.
std::vector<Vec2d> brute_force(const std::vector<Vec2d>& s, const Rect2d& r) {
  const double tol = 1e-9;
  auto dist = [](Vec2d a, Vec2d b) { return std::hypot(a.x - b.x, a.y - b.y); };
  auto nearest_two = [&](Vec2d p, double& d0, double& d1) {
    d0 = d1 = std::numeric_limits<double>::infinity();
    for (const Vec2d& q : s) {
      const double d = dist(p, q);
      if (d < d0) {
        d1 = d0;
        d0 = d;
      } else if (d < d1) {
        d1 = d;
      }
    }
  };
  std::vector<Vec2d> out;
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = i + 1; j < s.size(); ++j)
      for (std::size_t k = j + 1; k < s.size(); ++k) {
        const Vec2d a = s[i], b = s[j], c = s[k];
        const double den = 2 * (a.x * (b.y - c.y) + b.x * (c.y - a.y) + c.x * (a.y - b.y));
        if (std::fabs(den) < 1e-12) continue;
        const double a2 = a.x * a.x + a.y * a.y, b2 = b.x * b.x + b.y * b.y, c2 = c.x * c.x + c.y * c.y;
        const Vec2d o{(a2 * (b.y - c.y) + b2 * (c.y - a.y) + c2 * (a.y - b.y)) / den,
                      (a2 * (c.x - b.x) + b2 * (a.x - c.x) + c2 * (b.x - a.x)) / den};
        if (o.x < r.lo.x || o.x > r.hi.x || o.y < r.lo.y || o.y > r.hi.y) continue;
        double d0, d1;
        nearest_two(o, d0, d1);
        if (dist(o, a) <= d0 + tol) out.push_back(o);
      }
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      const Vec2d p = s[i], q = s[j];
      const Vec2d m{0.5 * (p.x + q.x), 0.5 * (p.y + q.y)}, d{-(q.y - p.y), q.x - p.x};
      std::vector<Vec2d> hits;
      if (d.x != 0)
        for (double x : {r.lo.x, r.hi.x}) hits.push_back({x, m.y + (x - m.x) / d.x * d.y});
      if (d.y != 0)
        for (double y : {r.lo.y, r.hi.y}) hits.push_back({m.x + (y - m.y) / d.y * d.x, y});
      for (const Vec2d& h : hits) {
        if (h.x < r.lo.x - tol || h.x > r.hi.x + tol || h.y < r.lo.y - tol || h.y > r.hi.y + tol) continue;
        double d0, d1;
        nearest_two(h, d0, d1);
        if (dist(h, p) <= d0 + tol) out.push_back(h);
      }
    }
  std::sort(out.begin(), out.end(), [](Vec2d a, Vec2d b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  std::vector<Vec2d> unique;
  for (const Vec2d& p : out) {
    bool dup = false;
    for (const Vec2d& u : unique) dup = dup || dist(p, u) < 1e-7;
    if (!dup) unique.push_back(p);
  }
  return unique;
}

TEST(VoronoiCandidates, RandomConfigurationsMatchBruteForce) {
  std::mt19937 rng(20020);
  std::uniform_real_distribution<double> coord(-0.5, 1.5);
  const Rect2d rect{{0, 0}, {1, 0.75}};
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vec2d> samples(2 + trial % 12);
    for (Vec2d& p : samples) p = {coord(rng), coord(rng)};
    const std::vector<Vec2d> got = voronoi_candidates(samples, rect);
    const std::vector<Vec2d> want = brute_force(samples, rect);
    ASSERT_TRUE(sorted_unique(got)) << "trial " << trial;
    // Match as sets: every reference point has a candidate nearby and vice versa.
    EXPECT_TRUE(covered(want, got, 1e-7)) << "trial " << trial << ": a Voronoi point is missing";
    EXPECT_TRUE(covered(got, want, 1e-7)) << "trial " << trial << ": a candidate is not a Voronoi point";
    EXPECT_EQ(got.size(), want.size()) << "trial " << trial;
    for (const Vec2d& c : got) {
      EXPECT_GE(c.x, rect.lo.x);
      EXPECT_LE(c.x, rect.hi.x);
      EXPECT_GE(c.y, rect.lo.y);
      EXPECT_LE(c.y, rect.hi.y);
    }
  }
}

TEST(VoronoiCandidates, GridConfigurationsMatchBruteForce) {
  // Subsets of a 5 x 5 lattice: many cocircular quadruples (zero-length
  // Voronoi edges, repeated circumcentres), bisectors along the sides and
  // Voronoi vertices on corners of the rectangle.
  std::mt19937 rng(42);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vec2d> samples;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        if (rng() % 3 == 0) samples.push_back({0.25 * i, 0.25 * j});
    const Rect2d rect = trial % 2 ? kUnit : Rect2d{{0.25, 0.25}, {0.75, 0.75}};
    const std::vector<Vec2d> got = voronoi_candidates(samples, rect);
    std::vector<Vec2d> want = samples.size() < 2 ? got : brute_force(samples, rect);
    // The reference keeps candidates on samples; the stage drops them.
    std::erase_if(want, [&](const Vec2d& p) {
      for (const Vec2d& s : samples)
        if (std::hypot(p.x - s.x, p.y - s.y) < 1e-7) return true;
      return false;
    });
    // As sets: coordinates equal up to rounding may sort either way.
    ASSERT_TRUE(sorted_unique(got)) << "trial " << trial;
    EXPECT_EQ(got.size(), want.size()) << "trial " << trial;
    EXPECT_TRUE(covered(want, got, 1e-9)) << "trial " << trial << ": a Voronoi point is missing";
    EXPECT_TRUE(covered(got, want, 1e-9)) << "trial " << trial << ": a candidate is not a Voronoi point";
  }
}

TEST(VoronoiCandidates, DeterministicUnderPermutation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(0, 1);
  std::vector<Vec2d> samples(40);
  for (Vec2d& p : samples) p = {coord(rng), coord(rng)};
  // Cocircular points too (a square grid), where the triangulation is not unique.
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) samples.push_back({0.125 + 0.25 * i, 0.125 + 0.25 * j});
  const std::vector<Vec2d> reference = voronoi_candidates(samples, kUnit);
  EXPECT_TRUE(sorted_unique(reference));
  for (int round = 0; round < 10; ++round) {
    std::shuffle(samples.begin(), samples.end(), rng);
    const std::vector<Vec2d> got = voronoi_candidates(samples, kUnit);
    ASSERT_EQ(got.size(), reference.size());
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(got[i] == reference[i]) << "round " << round;
  }
}

TEST(NextViewCandidates, AFloorSlabGivesVoronoiCandidatesInItsPlaneAtItsHeight) {
  // A slab flat along z at 1.7: one eye at its centre gives the four corners.
  const Box3d nav{{0, 0, 1.7}, {4, 2, 1.7}};
  const std::vector<Vec3d> eyes = {{2, 1, 1.7}};
  const std::vector<Vec3d> got = next_view_candidates(nav, eyes);
  EXPECT_EQ(got, (std::vector<Vec3d>{{0, 0, 1.7}, {0, 2, 1.7}, {4, 0, 1.7}, {4, 2, 1.7}}));
  // Flat along y (a y-up floor): the plane is x, z.
  const Box3d y_up{{0, 3, 0}, {2, 3, 2}};
  const std::vector<Vec3d> centre = {{1, 3, 1}};
  for (const Vec3d& p : next_view_candidates(y_up, centre)) EXPECT_EQ(p.y, 3.0);
  EXPECT_EQ(next_view_candidates(y_up, centre).size(), 4u);
}

TEST(NextViewCandidates, ABoxGivesItsLatticePointsNotYetSampled) {
  const Box3d nav{{0, 0, 0}, {2, 2, 2}};
  EXPECT_EQ(next_view_candidates(nav, {}).size(), 27u);
  const std::vector<Vec3d> eyes = {{1, 1, 1}, {0, 0, 0}, {5, 5, 5}};  // the last is no lattice point
  const std::vector<Vec3d> got = next_view_candidates(nav, eyes);
  ASSERT_EQ(got.size(), 25u);
  EXPECT_EQ(got.front(), (Vec3d{1, 0, 0}));  // x fastest, the sampled corner left out
  EXPECT_EQ(got.back(), (Vec3d{2, 2, 2}));
  EXPECT_EQ(std::count(got.begin(), got.end(), Vec3d{1, 1, 1}), 0);
}

}  // namespace
}  // namespace cellbake
