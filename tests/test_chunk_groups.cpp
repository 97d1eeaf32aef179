// Chunks merged into one for the group tiers (stages/chunk_groups.h): shared
// borders welded although each member stores them relative to its own
// origin, attributes kept, members without normals given face normals.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "fixture_memory_chunk_source.h"
#include "stages/chunk_groups.h"

namespace cellbake {
namespace {

// Two squares (two triangles each) meeting along x = 1 at 1000 m from the
// origin, each stored relative to an origin of its own (1000.3 and 1001.7),
// so the shared corners are different floats in the two chunks.
std::vector<Chunk> two_squares() {
  const auto square = [](double x0, std::int64_t id, const Vec3d& origin) {
    const Vec3d a{1000 + x0, 0, 0}, b{1001 + x0, 0, 0}, c{1001 + x0, 1, 0}, d{1000 + x0, 1, 0};
    return test::make_memory_chunk(id, {{a, b, c}, {a, c, d}}, origin);
  };
  return {square(0, 1, {1000.3, 0.1, 0}), square(1, 2, {1001.7, 0.9, 0})};
}

TEST(ChunkGroups, SharedBorderVerticesAreWeldedAcrossOrigins) {
  const std::vector<Chunk> squares = two_squares();
  const std::vector<const Chunk*> members = {&squares[0], &squares[1]};
  const Chunk merged = merge_chunks(members, 7);
  EXPECT_EQ(merged.id, 7);
  EXPECT_EQ(merged.triangle_count(), 4u);
  EXPECT_EQ(merged.positions.size(), 6u);  // 2 x 3 corners: the two on x = 1001 shared
  EXPECT_NEAR(merged.origin.x, 1001.0, 1e-9);
  EXPECT_NEAR(merged.bounds.lo.x, 1000.0, 1e-4);
  EXPECT_NEAR(merged.bounds.hi.x, 1002.0, 1e-4);
  // Every corner lies where the members put it (within float rounding).
  std::size_t corner = 0;
  for (const Chunk* m : members)
    for (std::uint32_t i : m->indices) {
      const Vec3d want = m->world(i), got = merged.world(merged.indices[corner++]);
      EXPECT_LT(length(want - got), 1e-4);
    }
  EXPECT_TRUE(merged.normals.empty());
  EXPECT_TRUE(merged.uvs.empty());
  EXPECT_TRUE(merged.materials.empty());
}

TEST(ChunkGroups, DifferingAttributesAreKeptAndMissingOnesFilled) {
  std::vector<Chunk> squares = two_squares();
  for (Rgba8& c : squares[0].colors) c = {255, 0, 0, 255};  // a seam of colour along the shared border
  squares[1].normals.assign(squares[1].positions.size(), Vec3f{0, 0, 1});
  squares[1].uvs.assign(squares[1].positions.size(), Uv{0.5f, 0.25f});
  squares[1].materials = {3, 3};
  const std::vector<const Chunk*> members = {&squares[0], &squares[1]};
  const Chunk merged = merge_chunks(members, 1);
  ASSERT_EQ(merged.normals.size(), merged.positions.size());
  ASSERT_EQ(merged.uvs.size(), merged.positions.size());
  EXPECT_EQ(merged.materials, (std::vector<std::uint32_t>{0, 0, 3, 3}));
  EXPECT_EQ(merged.positions.size(), 8u);  // 4 per square: the colours along the shared border differ
  for (std::size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = merged.indices[3 * t + std::size_t(k)];
      EXPECT_EQ(merged.colors[v], (Rgba8{255, 0, 0, 255}));
      EXPECT_FLOAT_EQ(std::abs(merged.normals[v].z), 1.0f);  // its face normal
      EXPECT_EQ(merged.uvs[v], (Uv{0, 0}));
    }
  EXPECT_EQ(merged.uvs[merged.indices[6]], (Uv{0.5f, 0.25f}));
}

TEST(ChunkGroups, BadInputIsRefused) {
  const std::vector<Chunk> squares = two_squares();
  EXPECT_THROW(merge_chunks({}, 1), std::invalid_argument);
  const std::vector<const Chunk*> with_null = {&squares[0], nullptr};
  EXPECT_THROW(merge_chunks(with_null, 1), std::invalid_argument);
  const std::vector<const Chunk*> one = {&squares[0]};
  EXPECT_THROW(merge_chunks(one, 1, 0.0), std::invalid_argument);
  Chunk broken = squares[0];
  broken.indices[0] = 99;
  const std::vector<const Chunk*> bad = {&broken};
  EXPECT_THROW(merge_chunks(bad, 1), std::invalid_argument);
}

}  // namespace
}  // namespace cellbake
