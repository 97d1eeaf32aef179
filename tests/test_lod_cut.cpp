// The view-dependent cut through chunk levels (stages/far/lod_cut.h), on chunks
// with analytic pixel sizes and level errors.
#include <gtest/gtest.h>

#include "stages/far/lod_cut.h"

using namespace cellbake;

namespace {

// A chunk of 1000 triangles with levels 1..3 of 500, 250, 125 triangles and
// errors 0.01, 0.02, 0.04 m, seen with `pixel_size` metres per pixel.
LodCutChunk halving_chunk(double pixel_size) {
  return {pixel_size, 1000, {{1, 0.01, 500}, {2, 0.02, 250}, {3, 0.04, 125}}};
}

}  // namespace

TEST(LodCut, EachChunkTakesItsCoarsestLevelWithinThePixelError) {
  // Pixel sizes 0.01 m (near) and 0.02 m (farther); the eye inside the third.
  const std::vector<LodCutChunk> chunks = {halving_chunk(0.01), halving_chunk(0.02), halving_chunk(0)};
  const LodCut exact = lod_cut_at_error(chunks, 0.4);
  EXPECT_EQ(exact.levels, (std::vector<int>{0, 0, 0}));
  EXPECT_EQ(exact.triangles, 3000u);
  const LodCut one = lod_cut_at_error(chunks, 1.0);  // 0.01 m near, 0.02 m farther
  EXPECT_EQ(one.levels, (std::vector<int>{1, 2, 0}));
  EXPECT_EQ(one.triangles, 500u + 250u + 1000u);
  const LodCut coarse = lod_cut_at_error(chunks, 100.0);
  EXPECT_EQ(coarse.levels, (std::vector<int>{3, 3, 0}));  // the chunk around the eye stays exact
  EXPECT_EQ(coarse.triangles, 125u + 125u + 1000u);
}

TEST(LodCut, TrianglesNeverGrowWithTheThreshold) {
  std::vector<LodCutChunk> chunks;
  for (int i = 1; i <= 20; ++i) chunks.push_back(halving_chunk(0.001 * i * i));
  std::uint64_t before = ~std::uint64_t{0};
  for (double e = 0; e < 50; e += 0.25) {
    const LodCut cut = lod_cut_at_error(chunks, e);
    EXPECT_LE(cut.triangles, before) << "at " << e << " px";
    before = cut.triangles;
  }
}

TEST(LodCut, ACutForATriangleCountIsTheFinestThatFits) {
  std::vector<LodCutChunk> chunks;
  for (int i = 1; i <= 20; ++i) chunks.push_back(halving_chunk(0.001 * i * i));
  chunks.push_back(halving_chunk(0));  // always exact: 1000
  for (std::uint64_t budget : {25000u, 12000u, 6000u, 4000u, 3500u}) {
    const LodCut cut = lod_cut_for_triangles(chunks, budget);
    EXPECT_LE(cut.triangles, budget);
    // Any smaller threshold draws more than the budget.
    if (cut.error_px > 0) EXPECT_GT(lod_cut_at_error(chunks, cut.error_px * (1 - 1e-9)).triangles, budget);
    EXPECT_EQ(cut.triangles, lod_cut_at_error(chunks, cut.error_px).triangles);
  }
  // Everything exact fits: threshold 0.
  EXPECT_EQ(lod_cut_for_triangles(chunks, 21000).error_px, 0.0);
  // Below the coarsest cut (20 x 125 + 1000 = 3500): the coarsest cut.
  const LodCut coarsest = lod_cut_for_triangles(chunks, 100);
  EXPECT_EQ(coarsest.triangles, 3500u);
  EXPECT_TRUE(lod_cut_for_triangles({}, 0).levels.empty());
}
