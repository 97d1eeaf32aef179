// The far field chosen per cube-face tile between exact far geometry and
// textured depth meshes (issue #13, stages/far/far_choice.h): the pure pieces
// (which tiles can see a box, which tile a depth-mesh triangle lies in,
// dropping a tile's triangles, a chunk's subset, the greedy choice on
// hand-built meshes and seen lists) and small end-to-end bakes of hand-built
// stores (an empty far field, one large wall, a dense field of 10^5 tiny
// triangles) with the Embree backend and, where the build has it, OSMesa.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <random>
#include <set>

#include "fixture_memory_chunk_source.h"
#include "fixture_room_obj.h"
#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"
#include "pipeline/sample_backend.h"
#include "runner/bake_runner.h"
#include "stages/chunk_subset.h"
#include "stages/far/far_choice.h"
#include "stages/render/gl_context.h"
#include "storage/cell_check.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "storage/sqlite_db.h"
#include "test_support.h"
#include "viewer/view_session.h"

namespace cellbake {
namespace {

constexpr std::uint32_t kAllFaceTiles = 0xFFFFu;

std::uint32_t tile_bit(int row, int column) { return 1u << (row * kFarTiles + column); }

// ---------------------------------------------------------------- tiles_seeing_box

// The tile of face `face` a direction falls in, or -1 when it is not on that face.
int direction_tile(int face, const Vec3d& d) {
  const FaceBasis b = cube_face_basis(face);
  const double f = dot(d, b.forward);
  if (f <= 0) return -1;
  const double s = dot(d, b.right) / f, t = dot(d, b.up) / f;
  if (std::abs(s) > 1 || std::abs(t) > 1) return -1;
  const int column = std::clamp(int((s + 1) / 2 * kFarTiles), 0, kFarTiles - 1);
  const int row = std::clamp(int((1 - t) / 2 * kFarTiles), 0, kFarTiles - 1);
  return row * kFarTiles + column;
}

Vec3d lerp_in(const Box3d& b, double u, double v, double w) {
  return {b.lo.x + u * (b.hi.x - b.lo.x), b.lo.y + v * (b.hi.y - b.lo.y), b.lo.z + w * (b.hi.z - b.lo.z)};
}

// Every tile some (eye, point) pair of a grid over both boxes looks through.
std::uint32_t brute_force_tiles(int face, const Box3d& eyes, const Box3d& box, int n = 6) {
  std::uint32_t tiles = 0;
  for (int a = 0; a <= n; ++a)
    for (int b = 0; b <= n; ++b)
      for (int c = 0; c <= n; ++c) {
        const Vec3d p = lerp_in(box, double(a) / n, double(b) / n, double(c) / n);
        for (int i = 0; i <= 1; ++i)
          for (int j = 0; j <= 1; ++j)
            for (int k = 0; k <= 1; ++k)
              if (const int tile = direction_tile(face, p - lerp_in(eyes, i, j, k)); tile >= 0) tiles |= 1u << tile;
      }
  return tiles;
}

TEST(FarChoiceTiles, BoxStraightAheadOfEachFaceHitsTheCentreTilesOnly) {
  const std::uint32_t centre = tile_bit(1, 1) | tile_bit(1, 2) | tile_bit(2, 1) | tile_bit(2, 2);
  const Box3d eye = Box3d::cube({0, 0, 0}, 0);
  for (int face = 0; face < kCubeFaces; ++face) {
    const FaceBasis b = cube_face_basis(face);
    const Box3d ahead = Box3d::cube(b.forward * 10.0, 1.0);  // s, t within +-0.11
    EXPECT_EQ(tiles_seeing_box(face, eye, ahead), centre) << "face " << face;
    const Box3d behind = Box3d::cube(b.forward * -10.0, 1.0);
    EXPECT_EQ(tiles_seeing_box(face, eye, behind), 0u) << "face " << face;
    // Right of centre, above the middle: s in [0.3, 0.7], t in [0.05, 0.45].
    Box3d off;
    off.expand(b.forward * 10.0 + b.right * 3.0 + b.up * 0.5);
    off.expand(b.forward * 10.0 + b.right * 7.0 + b.up * 4.5);
    EXPECT_EQ(tiles_seeing_box(face, eye, off), tile_bit(1, 2) | tile_bit(1, 3)) << "face " << face;
  }
  // The -X face cannot see a box ahead of +X, nor the side faces a box straight ahead.
  EXPECT_EQ(tiles_seeing_box(1, eye, Box3d::cube({10, 0, 0}, 1)), 0u);
  EXPECT_EQ(tiles_seeing_box(2, eye, Box3d::cube({10, 0, 0}, 1)), 0u);
  EXPECT_EQ(tiles_seeing_box(0, Box3d{}, Box3d::cube({10, 0, 0}, 1)), 0u);
  EXPECT_EQ(tiles_seeing_box(0, eye, Box3d{}), 0u);
}

TEST(FarChoiceTiles, AnEyeBoxWidensTheSetAndNeverMissesATile) {
  const Box3d ahead = Box3d::cube({10, 0, 0}, 1.0);
  const std::uint32_t from_point = tiles_seeing_box(0, Box3d::cube({0, 0, 0}, 0), ahead);
  const Box3d eyes{{-1, -5, -5}, {1, 5, 5}};  // s, t up to 6 / 9
  const std::uint32_t from_box = tiles_seeing_box(0, eyes, ahead);
  EXPECT_EQ(from_box & from_point, from_point);
  EXPECT_GT(std::popcount(from_box), std::popcount(from_point));
  EXPECT_EQ(from_box, kAllFaceTiles);
  // A box behind the +X face from every eye, even with eyes spread sideways.
  EXPECT_EQ(tiles_seeing_box(0, eyes, Box3d{{-12, -1, -1}, {-2, 1, 1}}), 0u);
  // A box straddling an eye box: some eye sees it through every tile of every face.
  for (int face = 0; face < kCubeFaces; ++face)
    EXPECT_EQ(tiles_seeing_box(face, Box3d::cube({0, 0, 0}, 1), Box3d::cube({0.5, 0, 0}, 0.2)), kAllFaceTiles);

  // Conservative: every tile a grid of eye/point pairs looks through is reported.
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> pos(-12, 12), size(0.1, 4);
  for (int trial = 0; trial < 200; ++trial) {
    const Box3d e = Box3d::cube({pos(rng) / 6, pos(rng) / 6, pos(rng) / 6}, size(rng) / 4);
    Box3d box;
    box.expand(Vec3d{pos(rng), pos(rng), pos(rng)});
    box.expand(box.lo + Vec3d{size(rng), size(rng), size(rng)});
    for (int face = 0; face < kCubeFaces; ++face) {
      const std::uint32_t got = tiles_seeing_box(face, e, box), seen = brute_force_tiles(face, e, box);
      EXPECT_EQ(got & seen, seen) << "trial " << trial << " face " << face;
    }
  }
}

// ---------------------------------------------------------------- triangle_tile / drop_geometry_tiles

// Appends one triangle with these texture coordinates (and positions
// telling the corners apart) to `mesh`, sharing no vertices.
void add_uv_triangle(FaceMesh& mesh, Uv a, Uv b, Uv c) {
  for (const Uv& uv : {a, b, c}) {
    mesh.indices.push_back(std::uint32_t(mesh.positions.size()));
    mesh.positions.push_back({1.0f, uv.u, uv.v});
    mesh.uvs.push_back(uv);
  }
}

// `count` small triangles wholly inside tile `tile`.
void add_tile_triangles(FaceMesh& mesh, int tile, int count) {
  const float u0 = float(tile % kFarTiles) / kFarTiles, v0 = float(tile / kFarTiles) / kFarTiles;
  const float step = 0.2f / kFarTiles / float(std::max(1, count));
  for (int k = 0; k < count; ++k) {
    const float u = u0 + 0.05f / kFarTiles + step * float(k), v = v0 + 0.4f / kFarTiles;
    add_uv_triangle(mesh, {u, v}, {u + 0.5f * step, v}, {u, v + 0.4f / kFarTiles});
  }
}

TEST(FarChoiceTiles, TriangleTileIsTheTileHoldingTheWholeTriangle) {
  FaceMesh m;
  add_uv_triangle(m, {0.30f, 0.55f}, {0.45f, 0.60f}, {0.35f, 0.70f});  // row 2, column 1
  add_uv_triangle(m, {0.20f, 0.10f}, {0.30f, 0.10f}, {0.22f, 0.20f});  // columns 0 and 1
  add_uv_triangle(m, {0.10f, 0.20f}, {0.20f, 0.20f}, {0.10f, 0.30f});  // rows 0 and 1
  add_uv_triangle(m, {0.25f, 0.00f}, {0.50f, 0.00f}, {0.50f, 0.25f});  // fills tile 1 up to its borders
  add_uv_triangle(m, {0.30f, 0.30f}, {0.50f, 0.30f}, {0.40f, 0.45f});  // touches the border u = 0.5 from the left
  add_uv_triangle(m, {0.50f, 0.30f}, {0.70f, 0.30f}, {0.60f, 0.45f});  // touches it from the right
  add_uv_triangle(m, {0.30f, 0.30f}, {0.501f, 0.30f}, {0.40f, 0.45f});  // a little over it
  add_uv_triangle(m, {0.80f, 0.80f}, {1.00f, 0.90f}, {0.90f, 1.00f});  // the last tile, up to the face edge
  add_uv_triangle(m, {0.00f, 0.00f}, {1.00f, 0.00f}, {0.00f, 1.00f});  // the whole face
  ASSERT_EQ(m.triangle_count(), 9u);
  EXPECT_EQ(triangle_tile(m, 0), 2 * kFarTiles + 1);
  EXPECT_EQ(triangle_tile(m, 1), -1);
  EXPECT_EQ(triangle_tile(m, 2), -1);
  EXPECT_EQ(triangle_tile(m, 3), 1);
  EXPECT_EQ(triangle_tile(m, 4), kFarTiles + 1);
  EXPECT_EQ(triangle_tile(m, 5), kFarTiles + 2);
  EXPECT_EQ(triangle_tile(m, 6), -1);
  EXPECT_EQ(triangle_tile(m, 7), kFarTilesPerFace - 1);
  EXPECT_EQ(triangle_tile(m, 8), -1);
  // Every pixel-sized triangle lies in the tile of its pixel's centre.
  const int size = 32;
  for (int row = 0; row < size; ++row)
    for (int col = 0; col < size; ++col) {
      FaceMesh p;
      const float u = float(col) / size, v = float(row) / size, d = 1.0f / size;
      add_uv_triangle(p, {u, v}, {u + d, v}, {u, v + d});
      ASSERT_EQ(triangle_tile(p, 0), pixel_tile(col, row, size)) << col << " " << row;
    }
}

TEST(FarChoiceTiles, DropGeometryTilesRemovesExactlyTheMaskedTilesTriangles) {
  FaceMesh m;
  // A shared-vertex strip: t0 in tile 0, t1 in tile 0 sharing t0's edge,
  // t2 spanning tiles 0 and 1 (sharing t1's vertex 2), t3 in tile 5, t4 in tile 15.
  m.uvs = {{0.05f, 0.05f}, {0.20f, 0.05f}, {0.05f, 0.20f}, {0.20f, 0.20f}, {0.40f, 0.10f},
           {0.30f, 0.30f}, {0.45f, 0.30f}, {0.30f, 0.45f}, {0.90f, 0.90f}, {0.95f, 0.90f}, {0.90f, 0.95f}};
  for (std::size_t v = 0; v < m.uvs.size(); ++v) m.positions.push_back({float(v), 2.0f * float(v), 1.0f});
  m.indices = {0, 1, 2, 1, 3, 2, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  const FaceMesh original = m;
  ASSERT_EQ(triangle_tile(m, 0), 0);
  ASSERT_EQ(triangle_tile(m, 1), 0);
  ASSERT_EQ(triangle_tile(m, 2), -1);
  ASSERT_EQ(triangle_tile(m, 3), 5);
  ASSERT_EQ(triangle_tile(m, 4), 15);

  FaceMesh same = m;
  EXPECT_EQ(drop_geometry_tiles(same, 0), 0u);
  EXPECT_EQ(same.indices, original.indices);
  EXPECT_EQ(drop_geometry_tiles(same, tile_bit(3, 0) | tile_bit(2, 2)), 0u);  // tiles without triangles
  EXPECT_EQ(same.positions, original.positions);

  EXPECT_EQ(drop_geometry_tiles(m, tile_bit(0, 0) | tile_bit(3, 3)), 3u);
  // Kept: t2 (vertices 2, 3, 4) and t3 (5, 6, 7), in order; vertices 0, 1, 8-10 are gone.
  ASSERT_EQ(m.triangle_count(), 2u);
  ASSERT_EQ(m.positions.size(), 6u);
  ASSERT_EQ(m.uvs.size(), 6u);
  const std::vector<std::uint32_t> kept_vertices = {2, 3, 4, 5, 6, 7};
  for (std::size_t k = 0; k < kept_vertices.size(); ++k) {
    EXPECT_EQ(m.positions[k], original.positions[kept_vertices[k]]) << k;
    EXPECT_EQ(m.uvs[k], original.uvs[kept_vertices[k]]) << k;
  }
  const std::vector<std::size_t> kept_triangles = {2, 3};
  for (std::size_t t = 0; t < kept_triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t now = m.indices[3 * t + std::size_t(c)];
      const std::uint32_t was = original.indices[3 * kept_triangles[t] + std::size_t(c)];
      EXPECT_EQ(m.positions[now], original.positions[was]);
      EXPECT_EQ(m.uvs[now], original.uvs[was]);
    }
  // The spanning triangle reaches tiles 0 and 1: it goes only with both.
  FaceMesh half = m;
  EXPECT_EQ(drop_geometry_tiles(half, tile_bit(0, 1) | tile_bit(2, 2)), 0u);
  EXPECT_EQ(drop_geometry_tiles(half, tile_bit(0, 0) | tile_bit(0, 1)), 1u);
  ASSERT_EQ(half.triangle_count(), 1u);
  EXPECT_EQ(half.positions.size(), 3u);
  EXPECT_EQ(half.positions[0], original.positions[5]);
  EXPECT_EQ(triangle_tile(half, 0), 5);
  EXPECT_EQ(drop_geometry_tiles(m, kAllFaceTiles), 2u);
  EXPECT_EQ(m.triangle_count(), 0u);
  EXPECT_TRUE(m.positions.empty());
  EXPECT_TRUE(m.uvs.empty());
  // A triangle along a tile border (u = 0.5) spans nothing.
  FaceMesh border;
  add_uv_triangle(border, {0.30f, 0.30f}, {0.50f, 0.30f}, {0.50f, 0.45f});
  EXPECT_EQ(drop_geometry_tiles(border, tile_bit(1, 2)), 0u);
  EXPECT_EQ(drop_geometry_tiles(border, tile_bit(1, 1)), 1u);
}

// ---------------------------------------------------------------- chunk_subset

TEST(FarChoiceSubset, KeepsTheChosenTrianglesWithAllTheirAttributes) {
  Chunk c;
  c.id = 42;
  c.origin = {100, -50, 7};
  // A 2 x 2 quad grid (9 shared vertices, 8 triangles).
  for (int j = 0; j <= 2; ++j)
    for (int i = 0; i <= 2; ++i) {
      const int v = j * 3 + i;
      c.positions.push_back({float(i), float(j), float(i * j)});
      c.colors.push_back({std::uint8_t(10 * v), std::uint8_t(200 - v), 7, 255});
      c.uvs.push_back({0.1f * float(v), 1.0f - 0.1f * float(v)});
      c.normals.push_back({0, float(v % 2), float(1 - v % 2)});
    }
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const std::uint32_t a = std::uint32_t(j * 3 + i), b = a + 1, d = a + 3, e = a + 4;
      c.indices.insert(c.indices.end(), {a, b, e, a, e, d});
    }
  c.materials = {0, 1, 2, 3, 4, 5, 6, 7};
  test::compute_memory_chunk_bounds(c);

  const std::vector<std::uint32_t> chosen = {2, 3, 6};
  const Chunk s = chunk_subset(c, chosen);
  EXPECT_EQ(s.id, c.id);
  EXPECT_EQ(s.origin, c.origin);
  ASSERT_EQ(s.triangle_count(), 3u);
  EXPECT_EQ(s.materials, (std::vector<std::uint32_t>{2, 3, 6}));
  // Triangles 2, 3 and 6 use vertices 1, 2, 5 / 1, 5, 4 / 4, 5, 8: five distinct.
  std::set<std::uint32_t> used;
  for (std::uint32_t t : chosen)
    for (int k = 0; k < 3; ++k) used.insert(c.indices[3 * t + std::size_t(k)]);
  ASSERT_EQ(s.positions.size(), used.size());
  ASSERT_EQ(s.colors.size(), used.size());
  ASSERT_EQ(s.uvs.size(), used.size());
  ASSERT_EQ(s.normals.size(), used.size());
  Box3d bounds;
  for (std::uint32_t v : used) bounds.expand(c.world(v));
  EXPECT_EQ(s.bounds, bounds);
  EXPECT_EQ(s.bounds, (Box3d{{101, -50, 7}, {102, -48, 11}}));
  // Vertices keep their original order.
  std::size_t k = 0;
  for (std::uint32_t v : used) EXPECT_EQ(s.positions[k++], c.positions[v]);
  for (std::size_t t = 0; t < chosen.size(); ++t)
    for (int corner = 0; corner < 3; ++corner) {
      const std::uint32_t now = s.indices[3 * t + std::size_t(corner)];
      const std::uint32_t was = c.indices[3 * chosen[t] + std::size_t(corner)];
      EXPECT_EQ(s.world(now), c.world(was));
      EXPECT_EQ(s.colors[now], c.colors[was]);
      EXPECT_EQ(s.uvs[now], c.uvs[was]);
      EXPECT_EQ(s.normals[now], c.normals[was]);
    }

  // Without uvs, normals and materials none appear.
  Chunk plain = test::make_memory_chunk(3, {{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, {{{5, 5, 5}, {6, 5, 5}, {5, 6, 5}}}});
  const Chunk p = chunk_subset(plain, std::vector<std::uint32_t>{1});
  EXPECT_TRUE(p.uvs.empty());
  EXPECT_TRUE(p.normals.empty());
  EXPECT_TRUE(p.materials.empty());
  EXPECT_EQ(p.bounds, (Box3d{{5, 5, 5}, {6, 6, 5}}));
  EXPECT_EQ(chunk_subset(plain, std::vector<std::uint32_t>{}).triangle_count(), 0u);

  EXPECT_THROW(chunk_subset(c, std::vector<std::uint32_t>{6, 1}), std::invalid_argument);
  EXPECT_THROW(chunk_subset(c, std::vector<std::uint32_t>{1, 1}), std::invalid_argument);
  EXPECT_THROW(chunk_subset(c, std::vector<std::uint32_t>{8}), std::invalid_argument);
  EXPECT_THROW(chunk_subset(c, std::vector<std::uint32_t>{0, 9}), std::invalid_argument);
}

// ---------------------------------------------------------------- choose_far_field

ChunkRef ref(std::int64_t id, std::uint32_t triangles, Box3d bounds = Box3d::cube({20, 0, 0}, 1)) {
  return {id, bounds, triangles};
}

// A seen chunk: `triangles` (first, first + 1, ...) each on `tiles`.
SeenChunk seen_triangles(std::int64_t id, std::uint32_t first, std::uint32_t count, std::uint16_t tiles) {
  SeenChunk s;
  s.id = id;
  s.tiles = tiles;
  for (std::uint32_t t = first; t < first + count; ++t) {
    s.triangles.push_back(t);
    s.triangle_tiles.push_back(tiles);
  }
  return s;
}

// One sample's inputs, owning what FarChoiceSample points to.
struct SampleInput {
  std::array<FaceMesh, kCubeFaces> meshes;
  std::array<std::vector<SeenChunk>, kCubeFaces> seen;
  FarChoiceSample view() const {
    FarChoiceSample s;
    for (int f = 0; f < kCubeFaces; ++f) {
      s.meshes[std::size_t(f)] = &meshes[std::size_t(f)];
      s.seen[std::size_t(f)] = &seen[std::size_t(f)];
    }
    return s;
  }
};

FarChoice choose(const std::vector<ChunkRef>& far, const std::vector<const SampleInput*>& inputs,
                 FarChoiceMode mode = FarChoiceMode::cheapest, const Box3d& eyes = Box3d::cube({0, 0, 0}, 1)) {
  std::vector<FarChoiceSample> samples;
  for (const SampleInput* s : inputs) samples.push_back(s->view());
  return choose_far_field(eyes, far, samples, mode);
}

void expect_same_choice(const FarChoice& a, const FarChoice& b) {
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceFarChoice &x = a.faces[std::size_t(f)], &y = b.faces[std::size_t(f)];
    EXPECT_EQ(x.geometry_tiles, y.geometry_tiles) << "face " << f;
    EXPECT_EQ(x.tdm_triangles, y.tdm_triangles) << "face " << f;
    EXPECT_EQ(x.replaced_triangles, y.replaced_triangles) << "face " << f;
    EXPECT_EQ(x.geometry_triangles, y.geometry_triangles) << "face " << f;
  }
  ASSERT_EQ(a.pieces.size(), b.pieces.size());
  for (std::size_t k = 0; k < a.pieces.size(); ++k) {
    EXPECT_EQ(a.pieces[k].chunk.id, b.pieces[k].chunk.id);
    EXPECT_EQ(a.pieces[k].triangles, b.pieces[k].triangles);
  }
  EXPECT_EQ(a.geometry_triangles, b.geometry_triangles);
}

TEST(FarChoiceChoose, WithoutSamplesEveryFarChunkIsGeometryOnTheTilesThatSeeIt) {
  const Box3d eyes = Box3d::cube({0, 0, 0}, 1);
  const std::vector<ChunkRef> far = {ref(3, 100, Box3d::cube({10, 0, 0}, 1)), ref(8, 50, Box3d{{-9, 4, -1}, {-7, 6, 1}}),
                                     ref(9, 7, Box3d{{-1, -1, 30}, {1, 1, 31}})};
  for (FarChoiceMode mode : {FarChoiceMode::cheapest, FarChoiceMode::tdm, FarChoiceMode::geometry}) {
    const FarChoice c = choose(far, {}, mode, eyes);
    ASSERT_EQ(c.pieces.size(), 3u);
    for (std::size_t k = 0; k < far.size(); ++k) {
      EXPECT_EQ(c.pieces[k].chunk.id, far[k].id);
      EXPECT_TRUE(c.pieces[k].triangles.empty());  // whole chunks
      EXPECT_EQ(c.pieces[k].triangle_count(), far[k].triangle_count);
    }
    EXPECT_EQ(c.geometry_triangles, 157u);
    for (int f = 0; f < kCubeFaces; ++f) {
      std::uint32_t expected = 0;
      std::uint64_t triangles = 0;
      for (const ChunkRef& r : far)
        if (const std::uint32_t t = tiles_seeing_box(f, eyes, r.bounds)) expected |= t, triangles += r.triangle_count;
      const FaceFarChoice& face = c.faces[std::size_t(f)];
      EXPECT_EQ(face.geometry_tiles, expected) << "face " << f;
      EXPECT_EQ(face.geometry_triangles, triangles) << "face " << f;
      EXPECT_EQ(face.tdm_triangles, 0u);
      EXPECT_EQ(face.replaced_triangles, 0u);
    }
    // The chunk ahead of +X is geometry there; +Z sees only the chunk above.
    EXPECT_NE(c.faces[0].geometry_tiles & tile_bit(1, 1), 0u);
    EXPECT_EQ(c.faces[4].geometry_triangles, 7u);
    EXPECT_EQ(c.faces[5].geometry_tiles, 0u);  // nothing below
  }
  // No far chunks, no samples: nothing at all.
  const FarChoice none = choose({}, {});
  EXPECT_TRUE(none.pieces.empty());
  for (const auto& f : none.faces) EXPECT_EQ(f.geometry_tiles, 0u);
}

// One large wall ahead of +X: two triangles seen on every tile (one per half),
// against a depth mesh of eight triangles per tile.
SampleInput wall_sample(std::int64_t wall_id) {
  SampleInput s;
  for (int tile = 0; tile < kFarTilesPerFace; ++tile) add_tile_triangles(s.meshes[0], tile, 8);
  SeenChunk seen = seen_triangles(wall_id, 0, 2, 0);
  seen.triangle_tiles = {0x137F, 0xFEC8};  // lower-left and upper-right halves, sharing the diagonal
  seen.tiles = 0xFFFF;
  s.seen[0] = {seen};
  return s;
}

TEST(FarChoiceChoose, OneLargeWallIsDrawnAsItsTwoTriangles) {
  const std::vector<ChunkRef> far = {ref(4, 2)};
  const SampleInput s = wall_sample(4);
  const FarChoice c = choose(far, {&s});
  EXPECT_EQ(c.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(c.faces[0].replaced_triangles, 128u);
  EXPECT_EQ(c.faces[0].tdm_triangles, 0u);
  EXPECT_EQ(c.faces[0].geometry_triangles, 2u);  // shared by all 16 tiles, counted once
  for (int f = 1; f < kCubeFaces; ++f) {
    EXPECT_EQ(c.faces[std::size_t(f)].geometry_tiles, 0u) << f;
    EXPECT_EQ(c.faces[std::size_t(f)].tdm_triangles, 0u) << f;
  }
  ASSERT_EQ(c.pieces.size(), 1u);
  EXPECT_EQ(c.pieces[0].chunk.id, 4);
  EXPECT_EQ(c.pieces[0].triangles, (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(c.geometry_triangles, 2u);

  // A depth-mesh triangle spanning tiles goes too when all its tiles take
  // geometry (a planar wall's depth mesh is a few such triangles).
  SampleInput spanning = s;
  add_uv_triangle(spanning.meshes[0], {0.1f, 0.1f}, {0.9f, 0.1f}, {0.1f, 0.9f});
  const FarChoice d = choose(far, {&spanning});
  EXPECT_EQ(d.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(d.faces[0].tdm_triangles, 0u);
  EXPECT_EQ(d.faces[0].replaced_triangles, 129u);
  FaceMesh dropped = spanning.meshes[0];
  EXPECT_EQ(drop_geometry_tiles(dropped, d.faces[0].geometry_tiles), 129u);
  EXPECT_EQ(dropped.triangle_count(), 0u);
  // Only two large triangles on +X, and the wall seen on the left half of
  // +Y, where a depth mesh of 40 triangles per tile lies; one triangle
  // spans that half and one the whole face.
  SampleInput big;
  add_uv_triangle(big.meshes[0], {0, 0}, {1, 0}, {1, 1});
  add_uv_triangle(big.meshes[0], {0, 0}, {1, 1}, {0, 1});
  big.seen[0] = {seen_triangles(4, 0, 2, 0xFFFF)};
  const std::uint16_t left = 0x3333;
  for (int tile = 0; tile < kFarTilesPerFace; ++tile)
    if (left >> tile & 1) add_tile_triangles(big.meshes[2], tile, 40);
  add_uv_triangle(big.meshes[2], {0, 0}, {0.5f, 0}, {0, 1});
  add_uv_triangle(big.meshes[2], {0, 0}, {1, 0}, {0, 1});
  big.seen[2] = {seen_triangles(4, 0, 1, left)};
  // With the whole cell, 2 triangles replace all 320 + 4: the spanning
  // triangles count too, since every tile they reach takes geometry (the
  // right half of +Y draws geometry with nothing in it, so the triangle over
  // the whole face goes).
  const FarChoice b = choose(far, {&big});
  EXPECT_EQ(b.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(b.faces[0].replaced_triangles, 2u);
  EXPECT_EQ(b.faces[0].tdm_triangles, 0u);
  EXPECT_EQ(b.faces[2].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(b.faces[2].replaced_triangles, 8u * 40 + 2);
  EXPECT_EQ(b.faces[2].tdm_triangles, 0u);
  EXPECT_EQ(b.geometry_triangles, 2u);

}

TEST(FarChoiceChoose, SpanningTrianglesCountInTheGainOfTheGroupThatDropsThem) {
  // 16 depth-mesh triangles within tiles and 4 spanning the whole face,
  // against 20 triangles of geometry seen on every tile: at factor 1 the
  // geometry pays only with the spanning triangles counted (20 <= 16 + 4).
  SampleInput s;
  for (int tile = 0; tile < kFarTilesPerFace; ++tile) add_tile_triangles(s.meshes[0], tile, 1);
  for (int k = 0; k < 4; ++k) add_uv_triangle(s.meshes[0], {0.01f * float(k), 0}, {1, 0}, {0, 1});
  s.seen[0] = {seen_triangles(3, 0, 20, std::uint16_t(kAllFaceTiles))};
  const FarChoice pays = choose({ref(3, 20)}, {&s});
  EXPECT_EQ(pays.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(pays.faces[0].replaced_triangles, 20u);
  EXPECT_EQ(pays.faces[0].tdm_triangles, 0u);
  EXPECT_EQ(pays.geometry_triangles, 20u);
  // One more triangle of geometry and it no longer pays anywhere.
  s.seen[0] = {seen_triangles(3, 0, 21, std::uint16_t(kAllFaceTiles))};
  const FarChoice declines = choose({ref(3, 21)}, {&s});
  EXPECT_EQ(declines.faces[0].geometry_tiles, 0u);
  EXPECT_EQ(declines.faces[0].tdm_triangles, 20u);
  EXPECT_EQ(declines.geometry_triangles, 0u);
}

TEST(FarChoiceChoose, NearFieldChunksInSeenListsCostNothing) {
  const std::vector<ChunkRef> far = {ref(4, 2)};
  const SampleInput plain = wall_sample(4);
  SampleInput with_near = plain;
  // Chunks 2 and 6 are near field (not among far_chunks): seen everywhere, 10^4 triangles each.
  with_near.seen[0].insert(with_near.seen[0].begin(), seen_triangles(2, 0, 10000, 0xFFFF));
  with_near.seen[0].push_back(seen_triangles(6, 0, 10000, 0xFFFF));
  SeenChunk whole_near;
  whole_near.id = 7;
  whole_near.tiles = 0xFFFF;
  with_near.seen[0].push_back(whole_near);
  const FarChoice a = choose(far, {&plain}), b = choose(far, {&with_near});
  expect_same_choice(a, b);
  EXPECT_EQ(b.faces[0].geometry_tiles, kAllFaceTiles);
  // Triangle numbers beyond the far chunk's count are not its own: ignored.
  SampleInput stray = plain;
  stray.seen[0][0].triangles.push_back(5);
  stray.seen[0][0].triangle_tiles.push_back(0xFFFF);
  expect_same_choice(a, choose(far, {&stray}));
}

TEST(FarChoiceChoose, TenThousandsOfTinyDistantTrianglesKeepTheDepthMeshes) {
  // 25 chunks of 4000 triangles, each triangle seen on one tile of +X
  // (6250 per tile); a depth mesh of 20 triangles per tile plus 100 spanning ones.
  std::vector<ChunkRef> far;
  SampleInput s;
  for (std::int64_t id = 1; id <= 25; ++id) {
    far.push_back(ref(id * 10, 4000));
    SeenChunk seen;
    seen.id = id * 10;
    for (std::uint32_t t = 0; t < 4000; ++t) {
      seen.triangles.push_back(t);
      seen.triangle_tiles.push_back(std::uint16_t(1u << ((t + std::uint32_t(id)) % kFarTilesPerFace)));
      seen.tiles |= seen.triangle_tiles.back();
    }
    s.seen[0].push_back(std::move(seen));
  }
  for (int tile = 0; tile < kFarTilesPerFace; ++tile) add_tile_triangles(s.meshes[0], tile, 20);
  for (int k = 0; k < 100; ++k) add_uv_triangle(s.meshes[0], {0.1f, 0.1f}, {0.9f, 0.1f + 0.001f * float(k)}, {0.1f, 0.9f});
  const FarChoice c = choose(far, {&s});
  for (int f = 0; f < kCubeFaces; ++f) EXPECT_EQ(c.faces[std::size_t(f)].geometry_tiles, 0u) << f;
  EXPECT_EQ(c.faces[0].tdm_triangles, 16u * 20 + 100);
  EXPECT_EQ(c.faces[0].replaced_triangles, 0u);
  EXPECT_TRUE(c.pieces.empty());
  EXPECT_EQ(c.geometry_triangles, 0u);
  // Forced, the same inputs make every seen triangle geometry.
  const FarChoice g = choose(far, {&s}, FarChoiceMode::geometry);
  EXPECT_EQ(g.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(g.geometry_triangles, 100000u);
  EXPECT_EQ(g.faces[0].replaced_triangles, 16u * 20 + 100);
  EXPECT_EQ(g.faces[0].tdm_triangles, 0u);
}

TEST(FarChoiceChoose, ASimplifiedLevelTakesTilesTheExactTrianglesCouldNot) {
  // A far wall of thin pipes: 4 chunks of 4000 triangles, 3000 of each seen
  // on the tiles of +X; the depth meshes hold 200 triangles a tile (3200).
  std::vector<ChunkRef> far;
  SampleInput s;
  for (std::int64_t id = 1; id <= 4; ++id) {
    far.push_back(ref(id, 4000));
    SeenChunk seen;
    seen.id = id;
    for (std::uint32_t t = 0; t < 3000; ++t) {
      seen.triangles.push_back(t);
      seen.triangle_tiles.push_back(std::uint16_t(1u << (t % kFarTilesPerFace)));
      seen.tiles |= seen.triangle_tiles.back();
    }
    s.seen[0].push_back(std::move(seen));
  }
  for (int tile = 0; tile < kFarTilesPerFace; ++tile) add_tile_triangles(s.meshes[0], tile, 200);
  std::vector<FarChoiceSample> samples = {s.view()};
  const Box3d eyes = Box3d::cube({0, 0, 0}, 1);
  // Exact: 12000 triangles against 3200: depth meshes everywhere.
  const FarChoice exact = choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 2.0);
  EXPECT_EQ(exact.faces[0].geometry_tiles, 0u);
  // Level 2 of each chunk, 700 triangles (2800 in all, whole chunks): every tile takes it.
  const std::vector<FarLodChoice> levels(4, FarLodChoice{2, 700});
  const FarChoice lod = choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 2.0, {}, {}, levels);
  EXPECT_EQ(lod.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(lod.geometry_triangles, 2800u);
  ASSERT_EQ(lod.pieces.size(), 4u);
  for (const FarPiece& p : lod.pieces) {
    EXPECT_EQ(p.level, 2);
    EXPECT_TRUE(p.triangles.empty());
    EXPECT_EQ(p.triangle_count(), 700u);
  }
  // A level with more triangles than were seen is not taken: the seen triangles stay exact.
  const std::vector<FarLodChoice> coarse(4, FarLodChoice{1, 3500});
  const FarChoice forced = choose_far_field(eyes, far, samples, FarChoiceMode::geometry, 2.0, {}, {}, coarse);
  ASSERT_EQ(forced.pieces.size(), 4u);
  for (const FarPiece& p : forced.pieces) EXPECT_EQ(p.level, 0);
  EXPECT_EQ(forced.geometry_triangles, 12000u);
  // One choice per far chunk, or none.
  EXPECT_THROW(choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 2.0, {}, {}, std::span<const FarLodChoice>(coarse).subspan(0, 2)),
               std::invalid_argument);
}

TEST(FarChoiceChoose, ALevelThatMayNotReplaceExactTrianglesOnlyTakesWhatTheyCouldNot) {
  // +X: chunk 1, 3000 of its 4000 triangles seen against 640 depth-mesh
  // triangles (exact too dear at a factor of 2, also for the whole cell);
  // -X: chunk 2, 100 of its 1000 seen against 640 (exact affordable). Each
  // has a level: 700 and 50 triangles.
  std::vector<ChunkRef> far = {ref(1, 4000), ref(2, 1000)};
  SampleInput s;
  for (int face = 0; face < 2; ++face) {
    SeenChunk seen;
    seen.id = face + 1;
    for (std::uint32_t t = 0; t < (face == 0 ? 3000u : 100u); ++t) {
      seen.triangles.push_back(t);
      seen.triangle_tiles.push_back(std::uint16_t(1u << (t % kFarTilesPerFace)));
      seen.tiles |= seen.triangle_tiles.back();
    }
    s.seen[std::size_t(face)].push_back(std::move(seen));
    for (int tile = 0; tile < kFarTilesPerFace; ++tile) add_tile_triangles(s.meshes[std::size_t(face)], tile, 40);
  }
  std::vector<FarChoiceSample> samples = {s.view()};
  const Box3d eyes = Box3d::cube({0, 0, 0}, 1);
  const auto level_of = [](const FarChoice& c, std::int64_t id) {
    for (const FarPiece& p : c.pieces)
      if (p.chunk.id == id) return p.level;
    return -1;
  };
  // Neither level may replace exact triangles: chunk 2 stays exact (its 100
  // seen triangles), chunk 1, which the exact choice could not pay for, takes its level.
  std::vector<FarLodChoice> levels = {{2, 700, false}, {1, 50, false}};
  const FarChoice kept = choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 2.0, {}, {}, levels);
  EXPECT_EQ(level_of(kept, 1), 2);
  EXPECT_EQ(level_of(kept, 2), 0);
  EXPECT_EQ(kept.geometry_triangles, 700u + 100u);
  EXPECT_EQ(kept.faces[0].geometry_tiles, kAllFaceTiles);
  EXPECT_EQ(kept.faces[1].geometry_tiles, kAllFaceTiles);
  // Chunk 2's level may replace: its 50 triangles take the place of the 100 seen.
  levels[1].replaces_exact = true;
  const FarChoice replaced = choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 2.0, {}, {}, levels);
  EXPECT_EQ(level_of(replaced, 1), 2);
  EXPECT_EQ(level_of(replaced, 2), 1);
  EXPECT_EQ(replaced.geometry_triangles, 700u + 50u);
}

TEST(FarChoiceChoose, AMixedFaceTakesGeometryOnlyWhereItIsCheaper) {
  // +Y face: tile 0 sees 2 triangles of chunk 5 against 20 depth-mesh
  // triangles; tile 5 sees 1000 triangles of chunk 6 against 20.
  // -Z face: tiles 1 and 2 see the same 10 triangles of chunk 7 against 6
  // each: neither pays alone, together they do (12 >= 10, counted once).
  const std::vector<ChunkRef> far = {ref(5, 2), ref(6, 1000), ref(7, 10)};
  SampleInput s;
  add_tile_triangles(s.meshes[2], 0, 20);
  add_tile_triangles(s.meshes[2], 5, 20);
  s.seen[2] = {seen_triangles(5, 0, 2, 1u << 0), seen_triangles(6, 0, 1000, 1u << 5)};
  add_tile_triangles(s.meshes[5], 1, 6);
  add_tile_triangles(s.meshes[5], 2, 6);
  s.seen[5] = {seen_triangles(7, 0, 10, (1u << 1) | (1u << 2))};
  const FarChoice c = choose(far, {&s});
  EXPECT_EQ(c.faces[2].geometry_tiles, 1u << 0);
  EXPECT_EQ(c.faces[2].replaced_triangles, 20u);
  EXPECT_EQ(c.faces[2].tdm_triangles, 20u);
  EXPECT_EQ(c.faces[2].geometry_triangles, 2u);
  EXPECT_EQ(c.faces[5].geometry_tiles, (1u << 1) | (1u << 2));
  EXPECT_EQ(c.faces[5].replaced_triangles, 12u);
  EXPECT_EQ(c.faces[5].tdm_triangles, 0u);
  EXPECT_EQ(c.faces[5].geometry_triangles, 10u);
  ASSERT_EQ(c.pieces.size(), 2u);
  EXPECT_EQ(c.pieces[0].chunk.id, 5);
  EXPECT_EQ(c.pieces[1].chunk.id, 7);
  EXPECT_EQ(c.pieces[1].triangles.size(), 10u);
  EXPECT_EQ(c.geometry_triangles, 12u);
  // The depth meshes lose exactly the geometry tiles' triangles.
  FaceMesh y = s.meshes[2];
  EXPECT_EQ(drop_geometry_tiles(y, c.faces[2].geometry_tiles), 20u);
  for (std::size_t t = 0; t < y.triangle_count(); ++t) EXPECT_EQ(triangle_tile(y, t), 5);

  // Mode tdm never takes geometry, whatever it would save.
  const SampleInput wall = wall_sample(4);
  const FarChoice tdm = choose({ref(4, 2)}, {&wall}, FarChoiceMode::tdm);
  EXPECT_EQ(tdm.faces[0].geometry_tiles, 0u);
  EXPECT_EQ(tdm.faces[0].tdm_triangles, 128u);
  EXPECT_TRUE(tdm.pieces.empty());
  const FarChoice mixed_tdm = choose(far, {&s}, FarChoiceMode::tdm);
  for (const auto& f : mixed_tdm.faces) EXPECT_EQ(f.geometry_tiles, 0u);
  EXPECT_EQ(mixed_tdm.faces[2].tdm_triangles, 40u);
  EXPECT_TRUE(mixed_tdm.pieces.empty());
}

TEST(FarChoiceChoose, TheGeometryFactorBuysExactnessWithTriangles) {
  // One tile: 30 seen triangles against 20 depth-mesh triangles.
  SampleInput s;
  add_tile_triangles(s.meshes[0], 3, 20);
  s.seen[0] = {seen_triangles(9, 0, 30, 1u << 3)};
  std::vector<FarChoiceSample> samples = {s.view()};
  const std::vector<ChunkRef> far = {ref(9, 30)};
  const Box3d eyes = Box3d::cube({0, 0, 0}, 1);
  EXPECT_EQ(choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 1.0).faces[0].geometry_tiles, 0u);
  EXPECT_EQ(choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 1.49).faces[0].geometry_tiles, 0u);
  EXPECT_EQ(choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 1.5).faces[0].geometry_tiles, 1u << 3);
  EXPECT_EQ(choose_far_field(eyes, far, samples, FarChoiceMode::cheapest, 2.0).geometry_triangles, 30u);
}

TEST(FarChoiceGrow, OneRingAddsTheTrianglesSharingAVertexWithTheirTiles) {
  // A strip of 6 triangles: t shares vertices with t - 2 .. t + 2.
  Chunk strip;
  strip.id = 3;
  for (int i = 0; i < 8; ++i) {
    strip.positions.push_back({float(i / 2), float(i % 2), 0});
    strip.colors.push_back({200, 200, 200, 255});
  }
  for (std::uint32_t t = 0; t < 6; ++t)
    for (std::uint32_t v : {t, t + 1, t + 2}) strip.indices.push_back(v);
  const VertexTriangles adjacency = vertex_triangles(strip);
  ASSERT_EQ(adjacency.offsets.size(), 9u);
  EXPECT_EQ(adjacency.offsets[8] - adjacency.offsets[7], 1u);  // the last vertex: triangle 5 only
  std::vector<std::uint16_t> scratch;
  SeenChunk seen = seen_triangles(3, 0, 1, 1u << 2);
  grow_seen_triangles(seen, strip, adjacency, 1, scratch);
  EXPECT_EQ(seen.triangles, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(seen.triangle_tiles, (std::vector<std::uint16_t>(3, 1u << 2)));
  EXPECT_EQ(seen.tiles, 1u << 2);
  grow_seen_triangles(seen, strip, adjacency, 1, scratch);  // a second ring from there
  EXPECT_EQ(seen.triangles, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
  // Tiles merge where rings meet; whole chunks and zero rings stay as they are.
  SeenChunk two = seen_triangles(3, 0, 1, 1u << 0);
  two.triangles.push_back(3);  // vertices 3, 4, 5: triangles 1 .. 5 share one
  two.triangle_tiles.push_back(1u << 7);
  grow_seen_triangles(two, strip, adjacency, 1, scratch);
  EXPECT_EQ(two.triangles, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(two.triangle_tiles,
            (std::vector<std::uint16_t>{1u << 0, (1u << 0) | (1u << 7), (1u << 0) | (1u << 7), 1u << 7, 1u << 7, 1u << 7}));
  SeenChunk whole;
  whole.id = 3;
  whole.tiles = 1;
  grow_seen_triangles(whole, strip, adjacency, 1, scratch);
  EXPECT_TRUE(whole.whole());
  SeenChunk none = seen_triangles(3, 0, 1, 1u);
  grow_seen_triangles(none, strip, adjacency, 0, scratch);
  EXPECT_EQ(none.triangles.size(), 1u);
}

TEST(FarChoiceGrow, AScratchReusedAcrossChunksIsLeftZeroAndGivesTheFreshResult) {
  // A strip of 40 triangles and a second, shorter strip: growing in the long
  // one must leave nothing behind that the short one (or a later call) reads.
  const auto make_strip = [](std::int64_t id, std::uint32_t triangles) {
    Chunk strip;
    strip.id = id;
    for (std::uint32_t i = 0; i < triangles + 2; ++i) {
      strip.positions.push_back({float(i / 2), float(i % 2), 0});
      strip.colors.push_back({200, 200, 200, 255});
    }
    for (std::uint32_t t = 0; t < triangles; ++t)
      for (std::uint32_t v : {t, t + 1, t + 2}) strip.indices.push_back(v);
    return strip;
  };
  const Chunk long_strip = make_strip(1, 40), short_strip = make_strip(2, 6);
  const VertexTriangles long_adjacency = vertex_triangles(long_strip), short_adjacency = vertex_triangles(short_strip);
  SeenChunk far_end = seen_triangles(1, 37, 1, 1u << 4);
  far_end.triangles.push_back(39);
  far_end.triangle_tiles.push_back(1u << 5);
  std::vector<std::uint16_t> reused;
  grow_seen_triangles(far_end, long_strip, long_adjacency, 2, reused);
  EXPECT_EQ(far_end.triangles, (std::vector<std::uint32_t>{33, 34, 35, 36, 37, 38, 39}));
  EXPECT_EQ(reused, std::vector<std::uint16_t>(40, 0));
  SeenChunk with_reused = seen_triangles(2, 5, 1, 1u << 1), with_fresh = with_reused;
  grow_seen_triangles(with_reused, short_strip, short_adjacency, 3, reused);
  std::vector<std::uint16_t> fresh;
  grow_seen_triangles(with_fresh, short_strip, short_adjacency, 3, fresh);
  EXPECT_EQ(with_reused, with_fresh);
  EXPECT_EQ(with_fresh.triangles, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(reused, std::vector<std::uint16_t>(40, 0));
}

TEST(FarChoiceChoose, ASampleThatSawAChunkWholeMakesItWhole) {
  const std::vector<ChunkRef> far = {ref(4, 2)};
  const SampleInput a = wall_sample(4);
  SampleInput b;
  add_tile_triangles(b.meshes[0], 3, 4);
  SeenChunk whole;
  whole.id = 4;
  whole.tiles = 1u << 3;
  b.seen[0] = {whole};
  const FarChoice c = choose(far, {&a, &b});
  ASSERT_EQ(c.pieces.size(), 1u);
  EXPECT_TRUE(c.pieces[0].triangles.empty());
  EXPECT_EQ(c.geometry_triangles, 2u);
  EXPECT_EQ(c.faces[0].replaced_triangles, 132u);
}

// Random depth meshes (`max_per_tile` triangles per tile at most, a few
// spanning tiles) and seen lists over 12 far chunks (and two near-field
// ones), for `count` samples.
struct RandomScenario {
  std::vector<ChunkRef> far;
  std::vector<SampleInput> samples;
};
RandomScenario random_scenario(unsigned seed, int count, int max_per_tile = 12) {
  std::mt19937 rng(seed);
  RandomScenario out;
  std::vector<ChunkRef>& far = out.far;
  for (std::int64_t id = 1; id <= 12; ++id) far.push_back(ref(id * 3, 5 + std::uint32_t(rng() % 60)));
  out.samples.resize(std::size_t(count));
  for (SampleInput& s : out.samples)
    for (int f = 0; f < kCubeFaces; ++f) {
      for (int tile = 0; tile < kFarTilesPerFace; ++tile)
        add_tile_triangles(s.meshes[std::size_t(f)], tile, int(rng() % unsigned(max_per_tile)));
      for (int k = 0; k < int(rng() % 4); ++k) add_uv_triangle(s.meshes[std::size_t(f)], {0, 0}, {0.6f, 0}, {0, 0.6f});
      for (std::int64_t id = 1; id <= 14; ++id) {
        if (rng() % 3 == 0) continue;
        const std::int64_t chunk = id <= 12 ? id * 3 : id * 3 + 1;  // 40 and 43: near field
        const std::uint32_t count = id <= 12 ? far[std::size_t(id - 1)].triangle_count : 30;
        if (rng() % 7 == 0) {
          SeenChunk w;
          w.id = chunk;
          w.tiles = std::uint32_t(rng() & 0xFFFF);
          s.seen[std::size_t(f)].push_back(w);
          continue;
        }
        SeenChunk c;
        c.id = chunk;
        for (std::uint32_t t = 0; t < count; ++t)
          if (rng() % 2) {
            c.triangles.push_back(t);
            c.triangle_tiles.push_back(std::uint16_t(1u << (rng() % kFarTilesPerFace) | 1u << (rng() % kFarTilesPerFace)));
            c.tiles |= c.triangle_tiles.back();
          }
        s.seen[std::size_t(f)].push_back(std::move(c));
      }
    }
  return out;
}

TEST(FarChoiceChoose, SampleOrderDoesNotChangeTheChoice) {
  // Five random samples; every permutation chooses the same.
  const RandomScenario scenario = random_scenario(2026, 5);
  const std::vector<ChunkRef>& far = scenario.far;
  const std::vector<SampleInput>& samples = scenario.samples;
  std::vector<const SampleInput*> order;
  for (const SampleInput& s : samples) order.push_back(&s);
  const FarChoice first = choose(far, order);
  int geometry_tiles = 0;
  for (const auto& f : first.faces) geometry_tiles += std::popcount(f.geometry_tiles);
  EXPECT_GT(geometry_tiles, 0);  // a choice with something to permute
  int permutations = 0;
  while (std::next_permutation(order.begin(), order.end()) && permutations < 30) {
    ++permutations;
    SCOPED_TRACE(permutations);
    expect_same_choice(first, choose(far, order));
  }
  std::reverse(order.begin(), order.end());
  expect_same_choice(first, choose(far, order));
  // And each figure adds up: kept + replaced = every depth-mesh triangle.
  for (int f = 0; f < kCubeFaces; ++f) {
    std::uint64_t all = 0;
    for (const SampleInput& s : samples) all += s.meshes[std::size_t(f)].triangle_count();
    EXPECT_EQ(first.faces[std::size_t(f)].tdm_triangles + first.faces[std::size_t(f)].replaced_triangles, all) << f;
  }
}

// The tiles of face `f` with nothing to draw: no depth-mesh triangle wholly
// inside and no seen far triangle or chunk on them, in any sample.
std::uint32_t empty_tiles(const RandomScenario& sc, int f) {
  std::uint32_t used = 0;
  for (const SampleInput& s : sc.samples) {
    const FaceMesh& m = s.meshes[std::size_t(f)];
    for (std::size_t t = 0; t < m.triangle_count(); ++t)
      if (const int tile = triangle_tile(m, t); tile >= 0) used |= 1u << tile;
    for (const SeenChunk& c : s.seen[std::size_t(f)]) {
      const bool is_far = std::any_of(sc.far.begin(), sc.far.end(), [&](const ChunkRef& r) { return r.id == c.id; });
      if (!is_far) continue;
      used |= c.tiles;
      for (std::uint16_t t : c.triangle_tiles) used |= t;
    }
  }
  return ~used & kAllFaceTiles;
}

// Calls `check` on 12 random cells in every mode at several geometry
// factors (each call traced with its seed, mode and factor).
void for_each_random_cell(const std::function<void(const RandomScenario&, FarChoiceMode, double)>& check) {
  for (unsigned seed = 1; seed <= 12; ++seed)
    for (const FarChoiceMode mode : {FarChoiceMode::cheapest, FarChoiceMode::tdm, FarChoiceMode::geometry})
      for (const double factor : {0.25, 1.0, 2.0, 8.0}) {
        SCOPED_TRACE(testing::Message() << "seed " << seed << " mode " << int(mode) << " factor " << factor);
        check(random_scenario(seed, 1 + int(seed % 4), seed % 2 ? 12 : 3), mode, factor);
      }
}

// Three samples whose every tile holds 40 depth-mesh triangles, and one far
// chunk (id 7) of `geometry` triangles seen on every tile.
std::vector<SampleInput> cheap_cell(std::uint32_t geometry) {
  SampleInput s;
  for (int f = 0; f < kCubeFaces; ++f) {
    for (int tile = 0; tile < kFarTilesPerFace; ++tile) add_tile_triangles(s.meshes[std::size_t(f)], tile, 40);
    s.seen[std::size_t(f)].push_back(seen_triangles(7, 0, geometry, std::uint16_t(kAllFaceTiles)));
  }
  return std::vector<SampleInput>(3, s);
}

// The samples' views with no mesh given (each to be asked for).
std::vector<FarChoiceSample> without_meshes(const std::vector<SampleInput>& inputs) {
  std::vector<FarChoiceSample> none;
  for (const SampleInput& in : inputs) {
    FarChoiceSample n = in.view();
    n.meshes.fill(nullptr);
    none.push_back(n);
  }
  return none;
}

TEST(FarChoiceLazy, MeshesOnDemandChooseTheSameGeometryAndKeepTheSameTiles) {
  // Random cells, every mode and several factors: the lazy choice (no mesh
  // given, each asked for on demand) draws the same far geometry, asks for
  // each face at most once, and differs from the full-count choice only on
  // tiles with nothing to draw (which it may mark as geometry).
  int asked_total = 0, possible_total = 0;
  for_each_random_cell([&](const RandomScenario& sc, FarChoiceMode mode, double factor) {
    std::vector<FarChoiceSample> full;
    for (const SampleInput& in : sc.samples) full.push_back(in.view());
    const std::vector<FarChoiceSample> none = without_meshes(sc.samples);
    const Box3d eyes = Box3d::cube({0, 0, 0}, 1);
    const FarChoice eager = choose_far_field(eyes, sc.far, full, mode, factor);
    std::set<std::pair<std::size_t, int>> asked;
    const FarChoice lazy = choose_far_field(
        eyes, sc.far, none, mode, factor, [&](std::size_t sample, int face) -> const FaceMesh& {
          EXPECT_TRUE(asked.insert({sample, face}).second) << "asked twice";
          return sc.samples.at(sample).meshes[std::size_t(face)];
        });
    asked_total += int(asked.size());
    possible_total += int(sc.samples.size()) * kCubeFaces;
    ASSERT_EQ(eager.pieces.size(), lazy.pieces.size());
    for (std::size_t k = 0; k < eager.pieces.size(); ++k) {
      EXPECT_EQ(eager.pieces[k].chunk.id, lazy.pieces[k].chunk.id);
      EXPECT_EQ(eager.pieces[k].triangles, lazy.pieces[k].triangles);
    }
    EXPECT_EQ(eager.geometry_triangles, lazy.geometry_triangles);
    if (mode == FarChoiceMode::tdm) EXPECT_EQ(asked.size(), sc.samples.size() * kCubeFaces);
    for (int f = 0; f < kCubeFaces; ++f) {
      const FaceFarChoice &e = eager.faces[std::size_t(f)], &l = lazy.faces[std::size_t(f)];
      const std::uint32_t nothing = empty_tiles(sc, f);
      EXPECT_EQ(e.geometry_tiles & ~l.geometry_tiles, 0u) << "face " << f;
      EXPECT_EQ(l.geometry_tiles & ~e.geometry_tiles & ~nothing, 0u) << "face " << f;
      EXPECT_LE(l.tdm_triangles, e.tdm_triangles) << "face " << f;
      EXPECT_EQ(l.geometry_triangles, e.geometry_triangles) << "face " << f;
      bool all_asked = true;
      for (std::size_t i = 0; i < sc.samples.size(); ++i) all_asked = all_asked && asked.count({i, f});
      if (!all_asked) EXPECT_EQ(l.geometry_tiles, kAllFaceTiles) << "face " << f << " not meshed but kept";
      if (l.geometry_tiles == e.geometry_tiles && all_asked) {
        EXPECT_EQ(l.tdm_triangles, e.tdm_triangles) << "face " << f;
        EXPECT_EQ(l.replaced_triangles, e.replaced_triangles) << "face " << f;
      }
    }
  });
  EXPECT_LT(asked_total, possible_total);  // some faces were never meshed
}

TEST(FarChoiceLazy, ACellWhoseGeometryIsCheapMeshesOneFace) {
  // Three samples whose every tile holds 40 depth-mesh triangles, and one far
  // chunk of 30 triangles seen on every tile: the first face meshed (sample
  // 0, face 0: 640 triangles) already pays for geometry everywhere.
  const std::vector<SampleInput> inputs = cheap_cell(30);
  const std::vector<FarChoiceSample> none = without_meshes(inputs);
  std::vector<std::pair<std::size_t, int>> asked;
  const std::vector<ChunkRef> far = {ref(7, 30)};
  const FarChoice lazy = choose_far_field(Box3d::cube({0, 0, 0}, 1), far, none, FarChoiceMode::cheapest, 2.0,
                                          [&](std::size_t sample, int face) -> const FaceMesh& {
                                            asked.push_back({sample, face});
                                            return inputs.at(sample).meshes[std::size_t(face)];
                                          });
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0], std::make_pair(std::size_t(0), 0));
  for (const FaceFarChoice& f : lazy.faces) {
    EXPECT_EQ(f.geometry_tiles, kAllFaceTiles);
    EXPECT_EQ(f.tdm_triangles, 0u);
  }
  EXPECT_EQ(lazy.faces[0].replaced_triangles, 640u);  // only the meshed face is counted
  EXPECT_EQ(lazy.faces[1].replaced_triangles, 0u);
  EXPECT_EQ(lazy.geometry_triangles, 30u);
}

TEST(FarChoiceLazy, BoundsDecideWholeFacesWithoutTheirMeshes) {
  // The random cells again, now with a bound source too (85 % of each mesh's
  // triangles, as an outline-only triangulation gives): the same geometry as
  // the full counts, each source asked at most once per face, a face's bound
  // before its mesh, never more meshes than without bounds, and some faces
  // decided by their bounds alone (drawn wholly as geometry).
  int meshes_with_bounds = 0, meshes_without = 0, bounded_only = 0;
  for_each_random_cell([&](const RandomScenario& sc, FarChoiceMode mode, double factor) {
    std::vector<FarChoiceSample> full;
    for (const SampleInput& in : sc.samples) full.push_back(in.view());
    const std::vector<FarChoiceSample> none = without_meshes(sc.samples);
    const Box3d eyes = Box3d::cube({0, 0, 0}, 1);
    const auto mesh_of = [&](std::size_t sample, int face) -> const FaceMesh& {
      return sc.samples.at(sample).meshes[std::size_t(face)];
    };
    const FarChoice eager = choose_far_field(eyes, sc.far, full, mode, factor);
    int lazy_meshes = 0;
    choose_far_field(eyes, sc.far, none, mode, factor, [&](std::size_t sample, int face) -> const FaceMesh& {
      ++lazy_meshes;
      return mesh_of(sample, face);
    });
    std::set<std::pair<std::size_t, int>> meshed, bounded;
    const FarChoice b = choose_far_field(
        eyes, sc.far, none, mode, factor,
        [&](std::size_t sample, int face) -> const FaceMesh& {
          EXPECT_TRUE(meshed.insert({sample, face}).second) << "mesh asked twice";
          return mesh_of(sample, face);
        },
        [&](std::size_t sample, int face) {
          EXPECT_TRUE(bounded.insert({sample, face}).second) << "bound asked twice";
          EXPECT_FALSE(meshed.count({sample, face})) << "bound asked after the mesh";
          return std::uint64_t(0.85 * double(mesh_of(sample, face).triangle_count()));
        });
    ASSERT_EQ(eager.pieces.size(), b.pieces.size());
    for (std::size_t k = 0; k < eager.pieces.size(); ++k) {
      EXPECT_EQ(eager.pieces[k].chunk.id, b.pieces[k].chunk.id);
      EXPECT_EQ(eager.pieces[k].triangles, b.pieces[k].triangles);
    }
    EXPECT_EQ(eager.geometry_triangles, b.geometry_triangles);
    EXPECT_LE(int(meshed.size()), lazy_meshes);
    meshes_with_bounds += int(meshed.size());
    meshes_without += lazy_meshes;
    for (const auto& [sample, face] : bounded)
      if (!meshed.count({sample, face})) {
        ++bounded_only;
        EXPECT_EQ(b.faces[std::size_t(face)].geometry_tiles, kAllFaceTiles) << "face " << face;
      }
    for (int f = 0; f < kCubeFaces; ++f)
      EXPECT_EQ(b.faces[std::size_t(f)].geometry_triangles, eager.faces[std::size_t(f)].geometry_triangles);
  });
  EXPECT_GT(bounded_only, 0);
  EXPECT_LT(meshes_with_bounds, meshes_without);
}

TEST(FarChoiceLazy, ACellWhoseGeometryIsCheapNeedsOneBoundAndNoMesh) {
  // The cheap cell of the test above with a bound source: the bound of the
  // first face (600 of its 640 triangles) pays for geometry everywhere, and
  // it is what that face reports replaced.
  const std::vector<SampleInput> inputs = cheap_cell(30);
  const std::vector<FarChoiceSample> none = without_meshes(inputs);
  int meshes = 0;
  std::vector<std::pair<std::size_t, int>> bounds;
  const std::vector<ChunkRef> far = {ref(7, 30)};
  const FarChoice c = choose_far_field(
      Box3d::cube({0, 0, 0}, 1), far, none, FarChoiceMode::cheapest, 2.0,
      [&](std::size_t sample, int face) -> const FaceMesh& {
        ++meshes;
        return inputs.at(sample).meshes[std::size_t(face)];
      },
      [&](std::size_t sample, int face) {
        bounds.push_back({sample, face});
        return std::uint64_t{600};
      });
  EXPECT_EQ(meshes, 0);
  ASSERT_EQ(bounds.size(), 1u);
  EXPECT_EQ(bounds[0], std::make_pair(std::size_t(0), 0));
  for (const FaceFarChoice& f : c.faces) {
    EXPECT_EQ(f.geometry_tiles, kAllFaceTiles);
    EXPECT_EQ(f.tdm_triangles, 0u);
  }
  EXPECT_EQ(c.faces[0].replaced_triangles, 600u);
  EXPECT_EQ(c.faces[1].replaced_triangles, 0u);
  EXPECT_EQ(c.geometry_triangles, 30u);
  // A geometry of 1300 triangles: one bound does not pay (2 * 600 < 1300),
  // two do. One of 30000 (more than twice all 11520 triangles): after one
  // bound, 18 faces of that size could not pay (2 * 18 * 600 < 30000), so
  // every mesh is asked for without more bounds; depth meshes everywhere.
  for (const std::uint32_t cost : {1300u, 30000u}) {
    const std::vector<SampleInput> heavy = cheap_cell(cost);
    const std::vector<FarChoiceSample> views = without_meshes(heavy);
    meshes = 0;
    bounds.clear();
    const FarChoice h = choose_far_field(
        Box3d::cube({0, 0, 0}, 1), std::vector<ChunkRef>{ref(7, cost)}, views, FarChoiceMode::cheapest, 2.0,
        [&](std::size_t sample, int face) -> const FaceMesh& {
          ++meshes;
          return heavy.at(sample).meshes[std::size_t(face)];
        },
        [&](std::size_t sample, int face) {
          bounds.push_back({sample, face});
          return std::uint64_t{600};
        });
    if (cost == 1300u) {
      EXPECT_EQ(meshes, 0);
      EXPECT_EQ(bounds.size(), 2u);
      EXPECT_EQ(h.geometry_triangles, 1300u);
    } else {
      EXPECT_EQ(meshes, 18);
      EXPECT_EQ(bounds.size(), 1u);
      EXPECT_EQ(h.geometry_triangles, 0u);
      for (const FaceFarChoice& f : h.faces) EXPECT_EQ(f.tdm_triangles, 3u * 640);
    }
  }
}

TEST(FarChoiceChoose, ParsesTheModeNames) {
  EXPECT_EQ(parse_far_choice_mode("cheapest"), FarChoiceMode::cheapest);
  EXPECT_EQ(parse_far_choice_mode("tdm"), FarChoiceMode::tdm);
  EXPECT_EQ(parse_far_choice_mode("geometry"), FarChoiceMode::geometry);
  EXPECT_THROW(parse_far_choice_mode("lod"), std::invalid_argument);
  BakeConfig c;
  EXPECT_THROW(apply_override(c, "far.choice=lod"), std::runtime_error);
  apply_override(c, "far.choice=tdm");
  EXPECT_EQ(c.far_choice, "tdm");
}


// ---------------------------------------------------------------- end to end

using Triangles = std::vector<std::array<Vec3d, 3>>;

Triangles box_triangles(const Box3d& b) {
  const auto corner = [&](int i) { return Vec3d{(i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z}; };
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  Triangles out;
  for (const auto& q : quads) {
    out.push_back({corner(q[0]), corner(q[1]), corner(q[2])});
    out.push_back({corner(q[0]), corner(q[2]), corner(q[3])});
  }
  return out;
}

Chunk coloured(Chunk c, Rgba8 colour) {
  for (std::size_t v = 0; v < c.colors.size(); ++v)
    c.colors[v] = {std::uint8_t(colour.r + (v % 3) * 20), std::uint8_t(colour.g + (v % 5) * 10), colour.b, 255};
  return c;
}

// A small box (12 triangles) around the cell centre: the near field.
Chunk near_box() { return coloured(test::make_memory_chunk(1, box_triangles(Box3d::cube({0, 0, 0}, 0.3))), {180, 60, 40}); }

// One large wall at x = 6 (two triangles), reaching far beyond the +X face.
Chunk wall() {
  const Vec3d a{6, -20, -20}, b{6, 20, -20}, c{6, 20, 20}, d{6, -20, 20};
  return coloured(test::make_memory_chunk(2, {{a, b, c}, {a, c, d}}), {40, 120, 160});
}

// 224 x 224 quads (100,352 tiny triangles, 7 cm) on a gently curved sheet
// around x = 8 filling the +X face, in chunks of 4032 triangles (9 rows).
std::vector<Chunk> tiny_field() {
  constexpr int n = 224, rows_per_chunk = 9;
  const auto at = [](int i, int j) {
    const double y = -8 + 16.0 * i / n, z = -8 + 16.0 * j / n;
    return Vec3d{8 + 0.4 * std::sin(0.5 * y) * std::cos(0.4 * z), y, z};
  };
  std::vector<Chunk> chunks;
  for (int j0 = 0; j0 < n; j0 += rows_per_chunk) {
    Triangles t;
    for (int j = j0; j < std::min(n, j0 + rows_per_chunk); ++j)
      for (int i = 0; i < n; ++i) {
        t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    chunks.push_back(coloured(test::make_memory_chunk(0, t, at(n / 2, j0)), {60, 150, std::uint8_t(4 * chunks.size())}));
  }
  return chunks;
}

// Writes `chunks` as a geometry store (ids 1, 2, ... in order) at DIR/NAME.
std::filesystem::path write_store(const test::TempDir& dir, const std::string& name, const std::vector<Chunk>& chunks) {
  const auto path = dir / name;
  GeometryStoreWriter w(path);
  StoreSummary summary;
  for (const Chunk& c : chunks) {
    w.add_chunk(c);
    summary.bounds.expand(c.bounds);
    summary.triangles += c.triangle_count();
    summary.vertices += c.positions.size();
    ++summary.chunks;
  }
  summary.content_hash = "far-choice-test-" + name + "-" + std::to_string(summary.triangles);
  w.finish(summary);
  return path;
}

// One 2 m cell centred on the origin (or two, at x = -1 and 1), a near
// budget of the near box's 12 triangles, 32-pixel PNG faces, sampled by `backend`,
// every far field sampled (far.geometry_below = 0).
BakeConfig cell_config(const test::TempDir& dir, const std::filesystem::path& store, const std::string& backend,
                       bool two_cells = false) {
  BakeConfig c;
  c.store = store;
  c.regions = {two_cells ? Box3d{{-2, -0.5, -0.5}, {2, 0.5, 0.5}} : Box3d{{-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}}};
  c.cell_size = 2;
  c.near_budget = 12;
  c.near_budget_fraction = 0;
  c.far_geometry_below = 0;
  c.face_size = 32;
  c.image_format = "png";
  c.sample_backend = backend;
  c.database = dir / "cells.db";
  return c;
}

CellRow baked_cell(const std::filesystem::path& db, std::int64_t id = 1) {
  const auto row = CellDb(db, CellDb::Mode::read_only).get_cell(id);
  if (!row) throw std::runtime_error("cell " + std::to_string(id) + " missing");
  return *row;
}

std::uint64_t tdm_triangles(const CellRow& row) {
  std::uint64_t n = 0;
  for (const SampleRow& s : row.samples)
    for (const FaceRow& f : s.faces) n += f.triangles;
  return n;
}

// The impostor against the truth from an off-centre eye in cell 1, looking
// past the near box at +X.
ViewResult render_diff(const std::filesystem::path& db) {
  ViewSession session(db);
  ViewRequest r;
  r.eye = {-0.8, 0.5, 0.3};
  r.look = {6, -0.5, -0.2};
  r.width = r.height = 96;
  return session.render(r, ViewMode::diff, stderr);
}

void expect_like_truth(const ViewResult& r) {
  EXPECT_EQ(r.cell_id, 1);
  EXPECT_FALSE(r.fallback) << r.fallback_reason;
  ASSERT_TRUE(r.metrics);
  EXPECT_GT(r.metrics->truth_covered_pixels, 96u * 96u / 2);
  EXPECT_GE(r.metrics->psnr_db, 40.0) << r.metrics->psnr_db;
}

TEST(FarChoiceBake, AnEmptyFarFieldStoresNoSamplesAndDrawsLikeTheTruth) {
  test::TempDir dir;
  BakeConfig c = cell_config(dir, write_store(dir, "s.db", {near_box(), wall()}), "embree");
  c.near_budget = 100000;
  c.near_budget_fraction = 0.1;  // 14 triangles: the whole model is near field
  c.far_geometry_below = 256;
  ASSERT_EQ(test::bake_quietly(c).cells_baked, 1u);
  const CellRow row = baked_cell(c.database);
  EXPECT_EQ(row.status, "done");
  EXPECT_EQ(row.near_triangles, 14u);
  EXPECT_TRUE(row.samples.empty());
  EXPECT_TRUE(row.far_geometry.empty());
  EXPECT_TRUE(row.far_choice.empty());
  EXPECT_EQ(row.far_triangles, 0u);
  EXPECT_EQ(row.far_geometry_triangles, 0u);
  const ViewResult r = render_diff(c.database);
  expect_like_truth(r);
  EXPECT_EQ(r.impostor_stats.far_triangles, 0u);
}

// The wall bake's row: the wall as far geometry (the two triangles the
// samples saw: the ray caster's hits or the rasteriser's primitive ids alike),
// no depth meshes left on +X, and an impostor like the truth.
void expect_wall_is_geometry(const BakeConfig& c) {
  ASSERT_EQ(test::bake_quietly(c).cells_baked, 1u);
  const CellRow row = baked_cell(c.database);
  ASSERT_EQ(row.status, "done") << row.error;
  ASSERT_EQ(row.far_geometry.size(), 1u);
  EXPECT_EQ(row.far_geometry[0].chunk_id, 2);
  EXPECT_EQ(row.far_geometry[0].triangles, 2u);
  EXPECT_FALSE(row.far_geometry[0].whole);
  EXPECT_FALSE(row.far_geometry[0].geometry.empty());
  EXPECT_EQ(row.far_geometry_triangles, 2u);
  ASSERT_FALSE(row.far_choice.empty());
  EXPECT_EQ(row.far_choice[0].face, 0);
  EXPECT_EQ(row.far_choice[0].geometry_tiles, kAllFaceTiles);
  std::uint64_t kept = 0;
  for (const FarChoiceRow& f : row.far_choice) kept += f.tdm_triangles;
  EXPECT_EQ(tdm_triangles(row), kept);
  EXPECT_EQ(row.far_triangles, kept);
  EXPECT_LE(kept, 8u) << "depth-mesh triangles kept beside the wall's two";
  std::printf("wall (%s): %llu depth-mesh triangles kept, %zu samples\n", c.sample_backend.c_str(),
              (unsigned long long)kept, row.samples.size());
  expect_like_truth(render_diff(c.database));
}

TEST(FarChoiceBake, OneLargeWallBehindANearObjectIsDrawnAsItsTrianglesEmbree) {
  test::TempDir dir;
  expect_wall_is_geometry(cell_config(dir, write_store(dir, "s.db", {near_box(), wall()}), "embree"));
}

TEST(FarChoiceBake, OneLargeWallBehindANearObjectIsDrawnAsItsTrianglesOsmesa) {
  if (!gl_backend_available(GlBackend::osmesa)) GTEST_SKIP() << "this build has no OSMesa";
  test::TempDir dir;
  expect_wall_is_geometry(cell_config(dir, write_store(dir, "s.db", {near_box(), wall()}), "osmesa"));
}

TEST(FarChoiceBake, GeometryModeTakesNoSamplesAndDrawsLikeTheTruth) {
  test::TempDir dir;
  BakeConfig c = cell_config(dir, write_store(dir, "s.db", {near_box(), wall()}), "embree");
  c.far_choice = "geometry";
  ASSERT_EQ(test::bake_quietly(c).cells_baked, 1u);
  const CellRow row = baked_cell(c.database);
  EXPECT_TRUE(row.samples.empty());
  ASSERT_EQ(row.far_geometry.size(), 1u);
  EXPECT_TRUE(row.far_geometry[0].whole);
  EXPECT_EQ(row.far_geometry_triangles, 2u);
  const ViewResult r = render_diff(c.database);
  expect_like_truth(r);
  EXPECT_TRUE(std::isinf(r.metrics->psnr_db)) << r.metrics->psnr_db;  // the same chunks, drawn the same way
}

TEST(FarChoiceBake, ADenseFieldOfTinyDistantTrianglesKeepsItsDepthMeshes) {
  test::TempDir dir;
  std::vector<Chunk> chunks = {near_box()};
  for (Chunk& c : tiny_field()) chunks.push_back(std::move(c));
  BakeConfig c = cell_config(dir, write_store(dir, "s.db", chunks), "embree");
  ASSERT_EQ(test::bake_quietly(c).cells_baked, 1u);
  const CellRow row = baked_cell(c.database);
  ASSERT_EQ(row.status, "done") << row.error;
  ASSERT_FALSE(row.samples.empty());
  std::uint64_t kept = 0;
  int geometry_tiles = 0;
  for (const FarChoiceRow& f : row.far_choice) {
    kept += f.tdm_triangles;
    geometry_tiles += std::popcount(f.geometry_tiles);
  }
  std::printf("dense field: %llu depth-mesh triangles kept, %d geometry tiles, %llu geometry triangles\n",
              (unsigned long long)kept, geometry_tiles, (unsigned long long)row.far_geometry_triangles);
  EXPECT_GT(kept, 0u);
  EXPECT_EQ(row.far_triangles, kept);
  // The face looking at the field keeps its depth meshes everywhere; at most
  // a few tiles where others see a sliver of it at a grazing angle draw
  // what they saw (measured with far.geometry_factor 2 and one seen ring:
  // 12 tiles, on the four faces that see the field edge-on).
  ASSERT_EQ(row.far_choice.at(0).face, 0);
  EXPECT_EQ(row.far_choice[0].geometry_tiles, 0u);
  EXPECT_GT(row.far_choice[0].tdm_triangles, 0u);
  EXPECT_LE(geometry_tiles, 16);
  EXPECT_LT(row.far_geometry_triangles, 1000u);  // of 100,352
}

// A far field of big triangles (a wall: 2 triangles over hundreds of pixel
// hits) is drawn as what the samples saw without meshing a face: the same
// far geometry the per-tile choice draws, no depth mesh stored, no delta
// scan reduced. The field of sub-pixel triangles above keeps the choice.
TEST(FarChoiceBake, ASparselySeenFarFieldIsDrawnAsGeometryWithoutMeshing) {
  test::TempDir dir;
  const auto store = write_store(dir, "s.db", {near_box(), wall()});
  BakeConfig shortcut = cell_config(dir, store, "embree"), choice = shortcut;
  shortcut.database = dir / "shortcut.db";
  choice.database = dir / "choice.db";
  choice.far_seen_geometry_per_hit = 0;
  ASSERT_EQ(test::bake_quietly(shortcut).cells_baked, 1u);
  ASSERT_EQ(test::bake_quietly(choice).cells_baked, 1u);
  const CellRow a = baked_cell(shortcut.database), b = baked_cell(choice.database);
  ASSERT_FALSE(a.samples.empty());
  EXPECT_EQ(a.far_triangles, 0u);
  EXPECT_EQ(tdm_triangles(a), 0u);
  EXPECT_EQ(a.stage_seconds.at("redundancy"), 0.0);  // never reduced
  EXPECT_GT(b.stage_seconds.at("redundancy"), 0.0);
  ASSERT_EQ(a.far_geometry.size(), b.far_geometry.size());
  for (std::size_t i = 0; i < a.far_geometry.size(); ++i) {
    EXPECT_EQ(a.far_geometry[i].chunk_id, b.far_geometry[i].chunk_id);
    EXPECT_EQ(a.far_geometry[i].triangles, b.far_geometry[i].triangles);
  }
  EXPECT_EQ(a.far_geometry_triangles, 2u);
  // Over the budget (here: any triangle at all), the per-tile choice decides.
  BakeConfig capped = shortcut;
  capped.database = dir / "capped.db";
  capped.far_seen_geometry_below = 1;
  ASSERT_EQ(test::bake_quietly(capped).cells_baked, 1u);
  EXPECT_GT(baked_cell(capped.database).stage_seconds.at("redundancy"), 0.0);
}

// The cell of `c` baked, and baked again into DIR/other.db with
// samples.visibility_face_size `visibility`.
std::pair<CellRow, CellRow> bake_twice(const test::TempDir& dir, const BakeConfig& c, int visibility) {
  BakeConfig other = c;
  other.samples_visibility_face_size = visibility;
  other.database = dir / "other.db";
  if (test::bake_quietly(c).cells_baked != 1 || test::bake_quietly(other).cells_baked != 1)
    throw std::runtime_error("bake_twice: a bake left its cell out");
  return {baked_cell(c.database), baked_cell(other.database)};
}

// A cell's first sample, then the rest, taken by the bake's own stages.
CellWork sampled_cell(const BakeConfig& c, const GeometryStore& store) {
  CellWork work;
  work.cell = enumerate_cells(c.regions, c.cell_size).at(0);
  run_cull_box(work, c, store);
  const CubeSamplerFactory factory(SampleBackend::embree, std::size_t{64} << 20);
  const std::unique_ptr<CubeSampler> sampler = factory.make();
  run_sample(work, c, store, *sampler);
  sampler->end_work();
  return work;
}

// The geometry triangles of the all-geometry far field the first `samples`
// of `work` saw, their seen sets grown (no cap on the count).
std::uint64_t sparse_geometry_of(const CellWork& work, std::size_t samples, BakeConfig c, const GeometryStore& store) {
  CellWork part;
  part.cell = work.cell;
  part.far_chunks = work.far_chunks;
  for (std::size_t i = 0; i < samples; ++i) {
    part.samples.emplace_back();
    part.samples.back().cube = work.samples[i].cube;
  }
  grow_seen_rings(part, c, store, 0, samples);
  c.far_seen_geometry_below = std::uint64_t{1} << 40;
  const std::optional<FarChoice> all = sparse_far_field(part, c, store);
  if (!all) throw std::runtime_error("the far field is not drawn as geometry");
  return all->geometry_triangles;
}

// A cell whose first sample sees a far field of big triangles takes the rest
// at samples.visibility_face_size: they only find what else is seen. The far
// field is the same two wall triangles as with every sample at full size.
TEST(FarChoiceBake, ASparseFirstSampleMakesTheLaterSamplesSmall) {
  test::TempDir dir;
  const auto path = write_store(dir, "s.db", {near_box(), wall()});
  BakeConfig c = cell_config(dir, path, "embree");
  c.face_size = 64;
  c.samples_visibility_face_size = 16;
  c.samples_max = 5;
  const GeometryStore store(path);
  const CellWork work = sampled_cell(c, store);
  ASSERT_GE(work.samples.size(), 2u);
  EXPECT_EQ(work.samples[0].cube.faces[0].size, 64);
  for (std::size_t i = 1; i < work.samples.size(); ++i)
    for (const CubeFace& f : work.samples[i].cube.faces) EXPECT_EQ(f.size, 16) << "sample " << i;
  ASSERT_TRUE(work.far.has_value());  // found while sampling, kept for the far choice
  EXPECT_TRUE(work.seen_grown);
  EXPECT_TRUE(work.chunk_facts.empty());
  EXPECT_EQ(work.far->geometry_triangles, 2u);

  const auto [small, big] = bake_twice(dir, c, 0);
  ASSERT_EQ(small.status, "done") << small.error;
  EXPECT_EQ(small.far_geometry_triangles, 2u);
  EXPECT_EQ(big.far_geometry_triangles, 2u);
  EXPECT_EQ(tdm_triangles(small), 0u);
  BakeConfig full = c;
  full.samples_visibility_face_size = 0;
  EXPECT_NE(cell_hashes(work.cell, c, "h").input, cell_hashes(work.cell, full, "h").input);
}

// Visibility samples at full size leave a cell's rows as they are without
// them (only their colours, never stored, are skipped).
TEST(FarChoiceBake, FullSizeVisibilitySamplesChangeNoRow) {
  test::TempDir dir;
  BakeConfig c = cell_config(dir, write_store(dir, "s.db", {near_box(), wall()}), "embree");
  c.face_size = 64;
  c.samples_max = 4;
  const auto [a, b] = bake_twice(dir, c, 64);
  ASSERT_EQ(a.status, "done") << a.error;
  EXPECT_EQ(a.content_hash, b.content_hash);
  EXPECT_EQ(a.samples.size(), b.samples.size());
}

// When the samples together see more than a far field drawn all as geometry
// may hold, the small ones are taken again at full size before the per-tile
// choice, their seen sets grown like the first's.
TEST(FarChoiceBake, SmallSamplesAreTakenAgainWhenTogetherTheySeeTooMuch) {
  test::TempDir dir;
  std::vector<Chunk> chunks = {near_box()};
  for (Chunk& ch : tiny_field()) chunks.push_back(std::move(ch));
  const auto path = write_store(dir, "s.db", chunks);
  BakeConfig c = cell_config(dir, path, "embree");
  c.face_size = 64;
  c.samples_max = 5;
  c.samples_void_threshold = 0;  // every sample samples.max allows
  c.far_seen_geometry_per_hit = 1e6;  // only the count decides
  const GeometryStore store(path);
  BakeConfig full = c;
  full.samples_visibility_face_size = 0;
  const CellWork reference = sampled_cell(full, store);
  ASSERT_EQ(reference.samples.size(), 5u);
  const std::uint64_t first = sparse_geometry_of(reference, 1, c, store);
  const std::uint64_t all = sparse_geometry_of(reference, 5, c, store);
  ASSERT_LT(first, all);
  c.far_seen_geometry_below = first;  // the first sample alone qualifies, not all of them
  c.samples_visibility_face_size = 16;
  const CellWork work = sampled_cell(c, store);
  ASSERT_EQ(work.samples.size(), 5u);
  for (const SampleWork& s : work.samples)
    for (const CubeFace& f : s.cube.faces) EXPECT_EQ(f.size, 64);
  EXPECT_FALSE(work.far.has_value());
  EXPECT_TRUE(work.seen_grown);
  // Each sample's seen sets grew once: the retaken ones as much as the first.
  CellWork retaken;
  retaken.cell = work.cell;
  retaken.far_chunks = work.far_chunks;
  retaken.samples.emplace_back();
  retaken.samples.back().cube = work.samples[0].cube;
  BakeConfig uncapped = c;
  uncapped.far_seen_geometry_below = std::uint64_t{1} << 40;
  EXPECT_EQ(sparse_far_field(retaken, uncapped, store)->geometry_triangles, first);
  c.database = dir / "cells.db";
  ASSERT_EQ(test::bake_quietly(c).cells_baked, 1u);
  const CellRow row = baked_cell(c.database);
  ASSERT_EQ(row.status, "done") << row.error;
  EXPECT_GT(row.stage_seconds.at("redundancy"), 0.0);  // the per-tile choice reduced the delta scans
}

TEST(FarChoiceBake, TheChoiceIsDeterministicAndPartOfTheInputHash) {
  test::TempDir dir;
  std::vector<Chunk> chunks = {near_box(), wall()};
  const auto store = write_store(dir, "s.db", chunks);
  BakeConfig one = cell_config(dir, store, "embree", true), two = one;
  one.database = dir / "one.db";
  two.database = dir / "two.db";
  ASSERT_EQ(test::bake_quietly(one, 1).cells_baked, 2u);
  ASSERT_EQ(test::bake_quietly(two, 2).cells_baked, 2u);
  const std::string hash = CellDb(one.database, CellDb::Mode::read_only).totals().content_hash;
  EXPECT_EQ(hash, CellDb(two.database, CellDb::Mode::read_only).totals().content_hash);
  for (std::int64_t id : {1, 2}) {
    const CellRow a = baked_cell(one.database, id), b = baked_cell(two.database, id);
    EXPECT_EQ(a.content_hash, b.content_hash) << id;
    EXPECT_FALSE(a.far_geometry.empty()) << id;
  }
  // The same configuration again: nothing to do.
  const BakeSummary again = test::bake_quietly(one, 2);
  EXPECT_EQ(again.cells_up_to_date, 2u);
  EXPECT_EQ(again.cells_baked, 0u);
  // Another far.choice re-bakes every cell (and changes what they hold).
  BakeConfig tdm = one;
  tdm.far_choice = "tdm";
  const BakeSummary changed = test::bake_quietly(tdm, 2);
  EXPECT_EQ(changed.cells_baked, 2u);
  EXPECT_EQ(changed.cells_up_to_date, 0u);
  const CellRow t = baked_cell(tdm.database);
  EXPECT_TRUE(t.far_geometry.empty());
  EXPECT_GT(t.far_triangles, 0u);
  EXPECT_NE(CellDb(tdm.database, CellDb::Mode::read_only).totals().content_hash, hash);
  // So does far.geometry_below.
  BakeConfig below = tdm;
  below.far_geometry_below = 1000;
  EXPECT_EQ(test::bake_quietly(below, 2).cells_baked, 2u);
}

TEST(FarChoiceBake, StatusCheckReportsACorruptFarGeometryBlob) {
  test::TempDir dir;
  const BakeConfig c = cell_config(dir, write_store(dir, "s.db", {near_box(), wall()}), "embree");
  ASSERT_EQ(test::bake_quietly(c).cells_baked, 1u);
  {
    CellDb db(c.database, CellDb::Mode::read_only);
    ASSERT_EQ(check_cell(db, 1), "");
    ASSERT_FALSE(db.get_cell(1)->far_geometry.at(0).whole);
  }
  const auto ok = test::run_cellbake("status --check '" + c.database.string() + "'");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  {
    SqliteDb db(c.database, SqliteDb::Mode::read_write_create);
    db.exec("UPDATE far_geometry SET geometry = substr(geometry, 1, length(geometry) - 1) WHERE cell_id = 1");
  }
  {
    CellDb db(c.database, CellDb::Mode::read_only);
    const std::string problem = check_cell(db, 1);
    EXPECT_NE(problem.find("far geometry of chunk 2"), std::string::npos) << problem;
  }
  const auto bad = test::run_cellbake("status --check '" + c.database.string() + "'");
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("far geometry of chunk 2"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("1 damaged cell(s)"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace cellbake
