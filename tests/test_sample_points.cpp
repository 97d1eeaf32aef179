// Initial sample points, the sample dependency tree and runtime sample
// selection: small hand-made cases with exact answers.
#include <gtest/gtest.h>

#include "stages/sample/sample_points.h"
#include "viewer/sample_selection.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

TEST(SamplePoints, FlatCellGivesCentreThenFourCorners) {
  const Box3d cell{{0, 0, -0.3}, {4, 4, 3.7}};
  const Box3d slab{{-10, -10, 1.7}, {10, 10, 1.7}};
  const Box3d nav = navigable_part(cell, slab);
  EXPECT_EQ(nav.lo.z, 1.7);
  EXPECT_EQ(nav.hi.z, 1.7);
  const auto points = initial_sample_points(nav, InitialSamples::corners_centre);
  ASSERT_EQ(points.size(), 5u);
  EXPECT_EQ(points[0], (Vec3d{2, 2, 1.7}));
  EXPECT_EQ(points[1], (Vec3d{0, 0, 1.7}));
  EXPECT_EQ(points[4], (Vec3d{4, 4, 1.7}));
  EXPECT_EQ(initial_sample_points(nav, InitialSamples::centre).size(), 1u);
  EXPECT_EQ(initial_sample_points(nav, InitialSamples::corners).size(), 4u);
}

TEST(SamplePoints, BoxCellGivesEightCornersAndAPointGivesItselfOnce) {
  const Box3d cell{{0, 0, 0}, {2, 2, 2}};
  EXPECT_EQ(initial_sample_points(cell, InitialSamples::corners_centre).size(), 9u);
  const Box3d point{{1, 1, 1}, {1, 1, 1}};
  EXPECT_EQ(initial_sample_points(point, InitialSamples::corners_centre).size(), 1u);
  EXPECT_THROW(initial_sample_points(Box3d{}, InitialSamples::centre), std::invalid_argument);
  EXPECT_TRUE(navigable_part(cell, Box3d{{5, 5, 5}, {6, 6, 6}}).empty());
}

TEST(SamplePoints, ParsesTheConfigNames) {
  EXPECT_EQ(parse_initial_samples("corners+centre"), InitialSamples::corners_centre);
  EXPECT_EQ(parse_initial_samples("centre"), InitialSamples::centre);
  EXPECT_THROW(parse_initial_samples("middle"), std::invalid_argument);
  EXPECT_STREQ(initial_samples_name(InitialSamples::corners), "corners");
}

TEST(SampleTree, CornersHangFromTheCentre) {
  const std::vector<Vec3d> p = {{2, 2, 0}, {0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {4, 4, 0}};
  EXPECT_EQ(sample_dependency_tree(p), (std::vector<int>{-1, 0, 0, 0, 0}));
}

TEST(SampleTree, CubedDistanceMakesChainsAlongALine) {
  // Centroid at 2: root is sample 2; with distance^3, 1 -> 2 and 0 -> 1 (1 + 1 < 8).
  const std::vector<Vec3d> p = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}};
  const auto parent = sample_dependency_tree(p);
  EXPECT_EQ(parent, (std::vector<int>{1, 2, -1, 2, 3}));
  EXPECT_EQ(sample_ancestors(parent, 0), (std::vector<int>{1, 2}));
  EXPECT_TRUE(sample_ancestors(parent, 2).empty());
  EXPECT_TRUE(sample_dependency_tree({}).empty());
}

TEST(SampleTree, DuplicatePointsStillFormATree) {
  const std::vector<Vec3d> p = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  const auto parent = sample_dependency_tree(p);
  EXPECT_EQ(parent[0], -1);
  for (int i = 1; i < 3; ++i) EXPECT_EQ(sample_ancestors(parent, i).back(), 0);
}

std::vector<SampleNode> star() {
  // Root 0 at the centre with 50 k triangles, four corners with 5 k each.
  return {{0, {2, 2, 0}, -1, 50000}, {1, {0, 0, 0}, 0, 5000}, {2, {4, 0, 0}, 0, 5000},
          {3, {0, 4, 0}, 0, 5000}, {4, {4, 4, 0}, 0, 5000}};
}

TEST(SampleSelection, NearestSampleComesWithItsAncestorsThenMoreWithinTheBudget) {
  SampleSelectionParams p;
  p.far_budget = 61000;
  p.root_factor = 0;
  const auto chosen = select_samples(star(), {0.2, 0.1, 0}, p);
  ASSERT_GE(chosen.size(), 2u);
  EXPECT_EQ(chosen[0], 1);
  EXPECT_EQ(chosen[1], 0);
  EXPECT_EQ(chosen.size(), 3u);  // 55 k + one more corner at 5 k fits in 61 k, a second does not
}

TEST(SampleSelection, MaxSamplesOneDrawsTheRootAlone) {
  SampleSelectionParams p;
  p.max_samples = 1;
  EXPECT_EQ(select_samples(star(), {0, 0, 0}, p), (std::vector<int>{0}));
  p.max_samples = 2;
  EXPECT_EQ(select_samples(star(), {4, 4, 0}, p), (std::vector<int>{4, 0}));
  p.far_budget = 0;  // the nearest chain is drawn whatever the budget
  p.root_factor = 0;
  p.max_samples = 0;
  EXPECT_EQ(select_samples(star(), {4, 4, 0}, p), (std::vector<int>{4, 0}));
  EXPECT_TRUE(select_samples({}, {0, 0, 0}, p).empty());
}

TEST(SampleSelection, TheBudgetGrowsToTwiceTheRootAlone) {
  SampleSelectionParams p;
  p.far_budget = 0;
  p.root_factor = 2.0;  // 100 k: the root (50 k) and all four corners (5 k each) fit
  EXPECT_EQ(select_samples(star(), {0, 0, 0}, p).size(), 5u);
  p.root_factor = 1.15;  // 57.5 k: the root and one corner
  EXPECT_EQ(select_samples(star(), {0, 0, 0}, p), (std::vector<int>{1, 0}));
}

TEST(SampleSelection, BoxInViewCullsBehindAndBeside) {
  RenderCamera c;  // looks down -z from the origin, 90 degrees
  EXPECT_TRUE(box_in_view(c, Box3d{{-1, -1, -5}, {1, 1, -4}}));
  EXPECT_FALSE(box_in_view(c, Box3d{{-1, -1, 4}, {1, 1, 5}}));
  EXPECT_FALSE(box_in_view(c, Box3d{{10, -1, -5}, {11, 1, -4}}));
  EXPECT_FALSE(box_in_view(c, Box3d{}));
}

}  // namespace
}  // namespace cellbake
