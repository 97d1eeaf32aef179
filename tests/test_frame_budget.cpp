// The viewer's frame-time control (issue #38): the triangles a frame may
// draw from recent frames (viewer/frame_time_budget.h), and which store
// levels a frame's chunks draw to fit them (viewer/chunk_level_budget.h).
#include <gtest/gtest.h>

#include <numeric>

#include "tests/fixture_memory_chunk_source.h"
#include "viewer/chunk_level_budget.h"
#include "viewer/frame_time_budget.h"

namespace cellbake {
namespace {

TEST(FrameTimeBudget, NoLimitUntilAFrameIsMeasuredThenTheTargetOverTheMedianCost) {
  FrameTimeBudget budget(60);
  EXPECT_EQ(budget.triangles(), 0u);
  budget.add(100, 0);       // drew nothing: ignored
  budget.add(0, 1000);      // no time: ignored
  EXPECT_EQ(budget.triangles(), 0u);
  budget.add(120, 200000);  // 0.6 us a triangle
  EXPECT_EQ(budget.triangles(), 100000u);
  budget.add(30, 100000);   // 0.3
  budget.add(90, 100000);   // 0.9: the median of three is 0.6 again, one odd frame moves nothing
  EXPECT_EQ(budget.triangles(), 100000u);
  EXPECT_THROW(FrameTimeBudget(0), std::invalid_argument);
}

TEST(FrameTimeBudget, FramesOfAFixedPlusPerTriangleCostConvergeOnTheTarget) {
  // A frame costs 30 ms plus 0.4 ms per 1,000 triangles; the scene has 500,000.
  FrameTimeBudget budget(70);
  std::uint64_t drawn = 500000;
  double ms = 0;
  for (int frame = 0; frame < 40; ++frame) {
    ms = 30 + 0.0004 * double(drawn);
    budget.add(ms, drawn);
    drawn = std::min<std::uint64_t>(500000, budget.triangles());
  }
  EXPECT_NEAR(ms, 70, 1.0);
  EXPECT_NEAR(double(drawn), 100000, 2500);
}

TEST(FrameTimeBudget, ChunksGetWhatTheOtherTrianglesLeave) {
  EXPECT_EQ(chunk_allowance(0, 5000), 0u);  // no limit
  EXPECT_EQ(chunk_allowance(100000, 30000), 70000u);
  EXPECT_EQ(chunk_allowance(100000, 150000), 1u);  // as coarse as the levels go
}

// A chunk of `n` triangles in a unit cube at x = `x`, with levels of n/2, n/4, ... (errors 1, 2, 4 cm).
Chunk cube_chunk(std::int64_t id, double x, int n) {
  std::vector<std::array<Vec3d, 3>> triangles;
  for (int i = 0; i < n; ++i) triangles.push_back({Vec3d{x, 0, 0}, Vec3d{x + 1, 0, 0}, Vec3d{x, 1, 1}});
  return test::make_memory_chunk(id, triangles);
}

void add_with_levels(test::MemoryChunkSource& source, std::int64_t id, double x, int n) {
  source.add(cube_chunk(id, x, n));
  for (int level = 1, m = n / 2; level <= 3; ++level, m /= 2)
    source.add_lod(id, level, cube_chunk(id, x, m), 0.01 * double(1 << (level - 1)));
}

TEST(ChunkLevelBudget, TheFarthestChunksCoarsenFirstAndTheCutFits) {
  test::MemoryChunkSource source;
  add_with_levels(source, 1, 2, 800);   // 2 m from the eye
  add_with_levels(source, 2, 20, 800);  // 20 m
  add_with_levels(source, 3, 50, 800);  // 50 m
  std::vector<ChunkDrawItem> items;
  for (std::int64_t id : {1, 2, 3}) {
    const auto chunk = source.load(id);
    items.push_back({id, 0, std::uint32_t(chunk->triangle_count()), chunk->bounds});
  }
  const Vec3d eye{0, 0.5, 0.5};
  const double per_metre = 2.0 / 720;  // a 90-degree view 720 pixels high
  const auto triangles = [&](const std::vector<int>& levels) {
    std::uint64_t sum = 0;
    for (std::size_t i = 0; i < items.size(); ++i)
      sum += levels[i] == 0 ? items[i].triangles : source.lods(items[i].chunk_id)[std::size_t(levels[i] - 1)].triangle_count;
    return sum;
  };
  // Enough room, or no limit: every chunk as the cell draws it.
  EXPECT_EQ(levels_for_triangle_budget(items, source, eye, per_metre, 0), (std::vector<int>{0, 0, 0}));
  EXPECT_EQ(levels_for_triangle_budget(items, source, eye, per_metre, 2400), (std::vector<int>{0, 0, 0}));
  // A little less: the farthest gives way first.
  const std::vector<int> some = levels_for_triangle_budget(items, source, eye, per_metre, 2000);
  EXPECT_LE(triangles(some), 2000u);
  EXPECT_EQ(some[0], 0);
  EXPECT_GT(some[2], 0);
  EXPECT_GE(some[2], some[1]);
  // Far too little: as coarse as the levels go.
  EXPECT_EQ(levels_for_triangle_budget(items, source, eye, per_metre, 10), (std::vector<int>{3, 3, 3}));
  // The chunk around the eye keeps its triangles.
  const std::vector<int> inside = levels_for_triangle_budget(items, source, Vec3d{2.5, 0.5, 0.5}, per_metre, 10);
  EXPECT_EQ(inside[0], 0);
}

TEST(ChunkLevelBudget, ASubsetOrALevelOnlyGoesToCoarserLevelsWithFewerTriangles) {
  test::MemoryChunkSource source;
  add_with_levels(source, 1, 20, 800);  // levels of 400, 200, 100 triangles
  const Box3d bounds = source.load(1)->bounds;
  // 150 seen triangles of the chunk: only level 3 (100) is smaller; level 2 drawn: only level 3 is coarser.
  const std::vector<ChunkDrawItem> items{{1, 0, 150, bounds}, {1, 2, 200, bounds}};
  EXPECT_EQ(levels_for_triangle_budget(items, source, Vec3d{0, 0, 0}, 0.01, 1), (std::vector<int>{3, 3}));
  const std::vector<ChunkDrawItem> small{{1, 0, 50, bounds}, {1, 3, 100, bounds}};
  EXPECT_EQ(levels_for_triangle_budget(small, source, Vec3d{0, 0, 0}, 0.01, 1), (std::vector<int>{0, 3}));
}

}  // namespace
}  // namespace cellbake
