// The far field's chunk levels (stages/chunk_lod.h): halving levels, locked
// borders (no cracks between chunks at different levels), then unlocked ones
// whose gaps the recorded error bounds, materials kept, and the level a
// distance allows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <tuple>

#include "pipeline/level_chunk_source.h"
#include "stages/chunk_lod.h"
#include "tests/fixture_memory_chunk_source.h"

namespace cellbake {
namespace {

// An n x n grid of quads over [0, 1]^2, z a smooth bump, as one chunk; the
// left half material 0, the right half material 1 when `two_materials`.
Chunk bumpy_patch(int n, bool two_materials) {
  Chunk c;
  c.id = 7;
  c.origin = {100, 200, 0};
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = float(i) / float(n), y = float(j) / float(n);
      c.positions.push_back({x, y, 0.05f * std::sin(3 * x) * std::cos(2 * y)});
      c.colors.push_back({std::uint8_t(i), std::uint8_t(j), 0, 255});
      c.bounds.expand(c.origin + Vec3d{x, y, 0.05 * std::sin(3.0 * x) * std::cos(2.0 * y)});
    }
  const auto v = [n](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      c.indices.insert(c.indices.end(), {v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j), v(i + 1, j + 1), v(i, j + 1)});
      if (two_materials) c.materials.insert(c.materials.end(), 2, i < n / 2 ? 0u : 1u);
    }
  return c;
}

using Edge = std::tuple<float, float, float, float, float, float>;

// The edges used by one triangle only, by the positions of their ends (sorted).
std::set<Edge> border_edges(const Chunk& c) {
  std::map<Edge, int> uses;
  for (std::size_t t = 0; t < c.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      Vec3f a = c.positions[c.indices[3 * t + std::size_t(k)]], b = c.positions[c.indices[3 * t + std::size_t(k + 1) % 3]];
      if (std::tie(b.x, b.y, b.z) < std::tie(a.x, a.y, a.z)) std::swap(a, b);
      ++uses[{a.x, a.y, a.z, b.x, b.y, b.z}];
    }
  std::set<Edge> out;
  for (const auto& [e, n] : uses)
    if (n == 1) out.insert(e);
  return out;
}

TEST(ChunkLod, LevelsHalveTheTrianglesAndKeepTheBorderExactly) {
  const Chunk chunk = bumpy_patch(40, false);  // 3200 triangles, 160 border edges
  ChunkLodParams locked_only;
  locked_only.unlocked_levels = false;
  const std::vector<ChunkLod> levels = build_chunk_lods(chunk, locked_only);
  ASSERT_GE(levels.size(), 3u);
  const std::set<Edge> border = border_edges(chunk);
  std::size_t previous = chunk.triangle_count();
  double previous_error = 0;
  for (std::size_t k = 0; k < levels.size(); ++k) {
    const ChunkLod& l = levels[k];
    EXPECT_EQ(l.ref.level, int(k) + 1);
    EXPECT_EQ(l.ref.triangle_count, l.chunk.triangle_count());
    EXPECT_LE(double(l.ref.triangle_count), 0.85 * double(previous)) << "level " << l.ref.level;
    EXPECT_GE(l.ref.error, previous_error) << "level " << l.ref.level;
    EXPECT_LT(l.ref.error, 0.1) << "level " << l.ref.level;  // the bump is 0.05 high
    EXPECT_EQ(l.chunk.id, chunk.id);
    EXPECT_EQ(l.chunk.origin, chunk.origin);
    EXPECT_EQ(l.chunk.colors.size(), l.chunk.positions.size());
    // The same border edges, vertex for vertex: a neighbour at any level meets it without a crack.
    EXPECT_EQ(border_edges(l.chunk), border) << "level " << l.ref.level;
    previous = l.ref.triangle_count, previous_error = l.ref.error;
  }
  // The border's 160 edges bound how far levels can go.
  EXPECT_GE(levels.back().ref.triangle_count, 80u);
}

// The distance from `p` to the nearest of `edges` (as segments).
double distance_to_edges(const Vec3f& p, const std::set<Edge>& edges) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [ax, ay, az, bx, by, bz] : edges) {
    const Vec3d a{ax, ay, az}, ab = Vec3d{bx, by, bz} - a, ap = Vec3d{p.x, p.y, p.z} - a;
    const double t = std::clamp(dot(ap, ab) / std::max(dot(ab, ab), 1e-30), 0.0, 1.0);
    best = std::min(best, length(ap - ab * t));
  }
  return best;
}

TEST(ChunkLod, PastTheLockedLevelsBordersMoveWithinHalfTheRecordedError) {
  const Chunk chunk = bumpy_patch(80, false);  // 12800 triangles, 320 border edges: the lock stops the levels
  ChunkLodParams locked_only;
  locked_only.unlocked_levels = false;
  const std::vector<ChunkLod> locked = build_chunk_lods(chunk, locked_only);
  ChunkLodParams gaps_only;  // errors doubled for the gaps alone, not for thin parts
  gaps_only.unlocked_error_scale = 2;
  const std::vector<ChunkLod> levels = build_chunk_lods(chunk, gaps_only);
  ASSERT_GT(levels.size(), locked.size());
  // The locked levels come first, the same; then levels the border lock stopped.
  for (std::size_t k = 0; k < locked.size(); ++k) {
    EXPECT_EQ(levels[k].ref.triangle_count, locked[k].ref.triangle_count);
    EXPECT_EQ(levels[k].ref.error, locked[k].ref.error);
  }
  EXPECT_LT(double(levels.back().ref.triangle_count), 0.5 * double(locked.back().ref.triangle_count));
  const std::set<Edge> border = border_edges(chunk);
  double previous_error = locked.back().ref.error;
  for (std::size_t k = locked.size(); k < levels.size(); ++k) {
    const ChunkLod& l = levels[k];
    EXPECT_EQ(l.ref.level, int(k) + 1);
    EXPECT_GE(l.ref.error, previous_error) << "level " << l.ref.level;
    EXPECT_LT(l.ref.error, 0.2) << "level " << l.ref.level;
    // A neighbour's border moves as far the other way: each side stays within
    // half the recorded error of where the chunks met, so the gap within all of it.
    for (const auto& [ax, ay, az, bx, by, bz] : border_edges(l.chunk)) {
      const Vec3f mid{0.5f * (ax + bx), 0.5f * (ay + by), 0.5f * (az + bz)};
      EXPECT_LE(distance_to_edges(mid, border), 0.5 * l.ref.error + 1e-6) << "level " << l.ref.level;
    }
    previous_error = l.ref.error;
  }
}

TEST(ChunkLod, AFlatPatchCollapsesWithoutError) {
  Chunk flat = bumpy_patch(20, false);
  for (Vec3f& p : flat.positions) p.z = 0;
  const std::vector<ChunkLod> levels = build_chunk_lods(flat);
  ASSERT_FALSE(levels.empty());
  for (const ChunkLod& l : levels) EXPECT_LT(l.ref.error, 1e-5) << "level " << l.ref.level;
}

TEST(ChunkLod, MaterialBordersStayWhereTheyAre) {
  const Chunk chunk = bumpy_patch(40, true);
  const std::vector<ChunkLod> levels = build_chunk_lods(chunk);
  ASSERT_GE(levels.size(), 2u);
  for (const ChunkLod& l : levels) {
    ASSERT_EQ(l.chunk.materials.size(), l.chunk.triangle_count());
    for (std::size_t t = 0; t < l.chunk.triangle_count(); ++t) {
      // Every corner of a material-0 triangle lies in the left half, of a material-1 one in the right.
      for (int k = 0; k < 3; ++k) {
        const float x = l.chunk.positions[l.chunk.indices[3 * t + std::size_t(k)]].x;
        if (l.chunk.materials[t] == 0)
          EXPECT_LE(x, 0.5f + 1e-6f) << "level " << l.ref.level << " triangle " << t;
        else
          EXPECT_GE(x, 0.5f - 1e-6f) << "level " << l.ref.level << " triangle " << t;
      }
    }
  }
}

TEST(ChunkLod, SmallOrBrokenChunksHaveNoLevels) {
  EXPECT_TRUE(build_chunk_lods(bumpy_patch(5, false)).empty());  // 50 triangles
  Chunk broken = bumpy_patch(40, false);
  broken.positions[100].y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(build_chunk_lods(broken).empty());
  Chunk bad_index = bumpy_patch(40, false);
  bad_index.indices[5] = 1u << 30;
  EXPECT_TRUE(build_chunk_lods(bad_index).empty());
}

TEST(ChunkLod, TheLevelIsTheCoarsestWithinThePixelBudget) {
  const std::vector<ChunkLodRef> levels = {{1, 0.001, 2000}, {2, 0.0035, 1000}, {3, 0.02, 500}};
  // 1 px of a 512-pixel face at 10 m: 10 * 2 / 512 = 0.039 m.
  EXPECT_NEAR(allowed_lod_error(10, 1, 512), 0.0390625, 1e-12);
  EXPECT_EQ(choose_lod_level(levels, allowed_lod_error(10, 1, 512)), 3);
  EXPECT_EQ(choose_lod_level(levels, allowed_lod_error(1, 1, 512)), 2);
  EXPECT_EQ(choose_lod_level(levels, allowed_lod_error(0.1, 1, 512)), 0);
  EXPECT_EQ(choose_lod_level(levels, allowed_lod_error(0, 1, 512)), 0);  // a view may stand at the chunk
  EXPECT_EQ(choose_lod_level({}, 1.0), 0);
}

TEST(LevelChunkSource, EachChunkIsItsCoarsestLevelWithinAPixelFromTheCell) {
  // Chunk 1 touches the cell, chunk 2 lies 100 m away; both have levels of
  // 1 mm and 0.5 m error. At 1 px of a 64-pixel face, the cell allows chunk 2
  // 100 * 2 / 64 = 3.1 m (level 2) and chunk 1 nothing (the chunk itself).
  test::MemoryChunkSource base;
  for (std::int64_t id : {1, 2}) {
    Chunk c = bumpy_patch(32, false);
    c.id = id;
    c.origin = id == 1 ? Vec3d{0, 0, 0} : Vec3d{100, 0, 0};
    test::compute_memory_chunk_bounds(c);
    const Chunk full = c;
    base.add(std::move(c));
    const std::vector<ChunkLod> levels = build_chunk_lods(full);
    ASSERT_GE(levels.size(), 2u);
    base.add_lod(id, 1, levels[0].chunk, 0.001);
    base.add_lod(id, 2, levels[1].chunk, 0.5);
  }
  const LevelChunkSource source(base, Box3d{{-1, -1, -1}, {0, 0, 0}}, 1.0, 64);
  const std::vector<ChunkRef> refs = source.query(source.model_bounds());
  ASSERT_EQ(refs.size(), 2u);
  EXPECT_EQ(refs[0].triangle_count, base.load(1)->triangle_count());
  EXPECT_EQ(refs[1].triangle_count, base.load_lod(2, 2)->triangle_count());
  EXPECT_LT(refs[1].triangle_count, base.load(2)->triangle_count());
  EXPECT_EQ(source.load(1), base.load(1));
  EXPECT_EQ(source.load(2), base.load_lod(2, 2));
  EXPECT_TRUE(source.lods(2).empty());
}

TEST(ChunkLod, TheMedianWidthIsTheHeightAcrossTheLongestEdge) {
  // Three right triangles with legs (1, h): the height across the
  // hypotenuse is h / sqrt(1 + h^2). A degenerate and a NaN triangle are skipped.
  Chunk chunk;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const double heights[] = {0.1, 0.2, 0.4};
  for (double h : heights) {
    const std::uint32_t base = std::uint32_t(chunk.positions.size());
    chunk.positions.push_back({0, 0, 0});
    chunk.positions.push_back({1, 0, 0});
    chunk.positions.push_back({0, float(h), 0});
    chunk.indices.insert(chunk.indices.end(), {base, base + 1, base + 2});
  }
  const std::uint32_t base = std::uint32_t(chunk.positions.size());
  chunk.positions.push_back({0, 0, 0});
  chunk.positions.push_back({2, 0, 0});
  chunk.positions.push_back({nan, 1, 0});
  chunk.indices.insert(chunk.indices.end(), {base, base + 1, base + 1, base, base + 1, base + 2});
  const double h = float(0.2);
  EXPECT_NEAR(median_triangle_width(chunk), h / std::sqrt(1 + h * h), 1e-6);
  EXPECT_EQ(median_triangle_width(Chunk{}), 0.0);
  // 1 px of a 512 px face at 10 m spans 2 * 10 / 512 = 0.039 m.
  EXPECT_TRUE(seen_subset_may_miss(0.03, 10.0, 1.0, 512));
  EXPECT_FALSE(seen_subset_may_miss(0.05, 10.0, 1.0, 512));
  EXPECT_FALSE(seen_subset_may_miss(0.03, 0.0, 1.0, 512));
}

}  // namespace
}  // namespace cellbake
