// Chunking invariants: every triangle in exactly one chunk, bounded chunk sizes,
// spatial coherence, determinism, duplicates kept together, degenerate detection.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "stages/chunking.h"

namespace cellbake {
namespace {

std::vector<Triangle> random_triangles(std::size_t n, unsigned seed, Vec3d offset = {0, 0, 0}) {
  std::mt19937_64 rng(seed);
  std::vector<Triangle> tris(n);
  for (auto& t : tris) {
    // Coordinates on a 1/1024 grid so translated copies are exactly representable.
    const Vec3d c{double(rng() % 100000) / 1024, double(rng() % 100000) / 1024, double(rng() % 20000) / 1024};
    for (int k = 0; k < 3; ++k)
      t.p[k] = offset + c + Vec3d{double(rng() % 512) / 1024, double(rng() % 512) / 1024, double(rng() % 512) / 1024};
  }
  return tris;
}

std::vector<TriangleKey> keys_of(const std::vector<Triangle>& tris) {
  std::vector<TriangleKey> keys;
  for (std::size_t i = 0; i < tris.size(); ++i) keys.push_back(make_triangle_key(tris[i], std::uint32_t(i)));
  return keys;
}

TEST(Chunking, EveryTriangleInExactlyOneChunkWithinSize) {
  auto tris = random_triangles(50000, 1);
  auto keys = keys_of(tris);
  auto ranges = split_into_chunks(keys, 2048);
  std::vector<int> seen(tris.size(), 0);
  std::size_t covered = 0;
  for (const auto& r : ranges) {
    EXPECT_LE(r.end - r.begin, 2048u);
    EXPECT_GT(r.end - r.begin, 1024u / 2);
    EXPECT_EQ(r.begin, covered);
    covered = r.end;
    for (std::size_t k = r.begin; k < r.end; ++k) {
      ++seen[keys[k].index];
      if (k > r.begin) {
        EXPECT_LT(keys[k - 1].index, keys[k].index);
      }
    }
  }
  EXPECT_EQ(covered, tris.size());
  for (int s : seen) EXPECT_EQ(s, 1);
}

TEST(Chunking, ChunksAreSpatiallyCoherent) {
  auto tris = random_triangles(40000, 2);
  auto keys = keys_of(tris);
  auto ranges = split_into_chunks(keys, 1000);
  // Median splits of a uniform cloud: total chunk volume ~ model volume, not many times it.
  Box3d all;
  double sum_volume = 0;
  for (const auto& r : ranges) {
    Box3d b;
    for (std::size_t k = r.begin; k < r.end; ++k)
      for (const auto& p : tris[keys[k].index].p) b.expand(p);
    const Vec3d e = b.extent();
    sum_volume += e.x * e.y * e.z;
    all.expand(b);
  }
  const Vec3d e = all.extent();
  EXPECT_LT(sum_volume, 3.0 * e.x * e.y * e.z);
}

TEST(Chunking, DeterministicRegardlessOfInputPermutationOfEqualKeys) {
  auto tris = random_triangles(20000, 3);
  auto k1 = keys_of(tris);
  auto k2 = k1;
  std::reverse(k2.begin(), k2.end());  // same keys, different starting order
  auto r1 = split_into_chunks(k1, 512);
  auto r2 = split_into_chunks(k2, 512);
  ASSERT_EQ(r1.size(), r2.size());
  for (std::size_t i = 0; i < k1.size(); ++i) EXPECT_EQ(k1[i].index, k2[i].index);
}

TEST(Chunking, TranslatedModelSplitsIdentically) {
  const Vec3d offset{1e6, -2e6, 5e5};
  auto a = random_triangles(20000, 4);
  auto b = random_triangles(20000, 4, offset);
  auto ka = keys_of(a), kb = keys_of(b);
  auto ra = split_into_chunks(ka, 1000), rb = split_into_chunks(kb, 1000);
  ASSERT_EQ(ra.size(), rb.size());
  for (std::size_t i = 0; i < ka.size(); ++i) ASSERT_EQ(ka[i].index, kb[i].index);
  // Chunk geometry relative to the chunk origin agrees to float rounding.
  for (std::size_t c = 0; c < ra.size(); c += 7) {
    std::vector<const Triangle*> ta, tb;
    for (std::size_t k = ra[c].begin; k < ra[c].end; ++k) {
      ta.push_back(&a[ka[k].index]);
      tb.push_back(&b[kb[k].index]);
    }
    Chunk ca = build_chunk(ta), cb = build_chunk(tb);
    ASSERT_EQ(ca.positions.size(), cb.positions.size());
    ASSERT_EQ(ca.indices, cb.indices);
    EXPECT_NEAR(cb.origin.x - ca.origin.x, offset.x, 1e-9);
    for (std::size_t v = 0; v < ca.positions.size(); ++v) {
      EXPECT_NEAR(ca.positions[v].x, cb.positions[v].x, 1e-6);
      EXPECT_NEAR(ca.positions[v].y, cb.positions[v].y, 1e-6);
      EXPECT_NEAR(ca.positions[v].z, cb.positions[v].z, 1e-6);
    }
  }
}

TEST(Chunking, DuplicatesStayInOneChunk) {
  auto tris = random_triangles(5000, 5);
  // 300 copies of one triangle (corners rotated) scattered through the input.
  Triangle dup = tris[17];
  for (int i = 0; i < 300; ++i) {
    Triangle t = dup;
    std::rotate(t.p.begin(), t.p.begin() + (i % 3), t.p.end());
    tris.insert(tris.begin() + (i * 13) % tris.size(), t);
  }
  auto keys = keys_of(tris);
  auto ranges = split_into_chunks(keys, 128);
  std::set<std::size_t> chunks_with_dup;
  for (std::size_t c = 0; c < ranges.size(); ++c)
    for (std::size_t k = ranges[c].begin; k < ranges[c].end; ++k)
      if (same_corners(tris[keys[k].index], dup)) chunks_with_dup.insert(c);
  EXPECT_EQ(chunks_with_dup.size(), 1u);
}

TEST(Chunking, DegenerateTriangles) {
  Triangle t;
  t.p = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}};
  EXPECT_FALSE(is_degenerate(t));
  t.p = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{2, 0, 0}};  // collinear
  EXPECT_TRUE(is_degenerate(t));
  t.p = {Vec3d{5, 5, 5}, Vec3d{5, 5, 5}, Vec3d{5, 5, 5}};  // a point
  EXPECT_TRUE(is_degenerate(t));
  t.p = {Vec3d{1e6, 1e6, 0}, Vec3d{1e6 + 0.001, 1e6, 0}, Vec3d{1e6, 1e6 + 0.001, 0}};  // small but real, far out
  EXPECT_FALSE(is_degenerate(t));
}

TEST(Chunking, BuildChunkSharesVerticesAndKeepsColours) {
  Triangle a, b;
  a.p = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}};
  b.p = {Vec3d{1, 0, 0}, Vec3d{1, 1, 0}, Vec3d{0, 1, 0}};
  a.color = {Rgba8{255, 0, 0, 255}, Rgba8{255, 0, 0, 255}, Rgba8{255, 0, 0, 255}};
  b.color = a.color;
  Chunk c = build_chunk({&a, &b});
  EXPECT_EQ(c.positions.size(), 4u);
  EXPECT_EQ(c.indices.size(), 6u);
  EXPECT_TRUE(c.uvs.empty());
  EXPECT_TRUE(c.materials.empty());
  EXPECT_EQ(c.origin, (Vec3d{0.5, 0.5, 0}));
  for (std::size_t i = 0; i < 6; ++i) {
    const Vec3d w = c.world(c.indices[i]);
    const Vec3d expect = (i < 3 ? a : b).p[i % 3];
    EXPECT_EQ(w, expect);
  }
}

}  // namespace
}  // namespace cellbake
