// Tests of the panoramic sampler and the offscreen chunk renderer with
// analytic answers: an eye at the centre of a closed box of side 2 sees planar
// depth 1 on every face, whatever the box's distance from the world origin.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <thread>

#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_sample_cube.h"
#include "stages/sample/sample.h"
#include "tests/fixture_chunk_source.h"

namespace cellbake {
namespace {

using test::chunk_from_triangles;
using test::flat_triangle;
using test::InMemoryChunkSource;

const std::array<Rgba8, 6> kWallColors = {Rgba8{255, 0, 0, 255},   Rgba8{0, 255, 0, 255},
                                          Rgba8{0, 0, 255, 255},   Rgba8{255, 255, 0, 255},
                                          Rgba8{0, 255, 255, 255}, Rgba8{255, 0, 255, 255}};

// The wall of `box` facing cube face `face` from inside (face 0 = the x = hi.x wall, ...), two triangles.
std::vector<Triangle> box_wall(const Box3d& box, int face, Rgba8 color) {
  const int axis = face / 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
  const double w = face % 2 == 0 ? box.hi[axis] : box.lo[axis];
  std::array<Vec3d, 4> q;
  const double us[4] = {box.lo[u], box.hi[u], box.hi[u], box.lo[u]};
  const double vs[4] = {box.lo[v], box.lo[v], box.hi[v], box.hi[v]};
  for (int i = 0; i < 4; ++i) {
    q[i][axis] = w;
    q[i][u] = us[i];
    q[i][v] = vs[i];
  }
  return {flat_triangle(q[0], q[1], q[2], color), flat_triangle(q[0], q[2], q[3], color)};
}

// A closed box of side 2 around `centre`: chunk id face + 1 holds wall `face`.
// Chunk origins sit off the float32 grid of large coordinates, as ingest's would.
void add_closed_box(InMemoryChunkSource& source, const Vec3d& centre) {
  const Box3d box = Box3d::cube(centre, 1.0);
  for (int face = 0; face < kCubeFaces; ++face)
    source.add(chunk_from_triangles(face + 1, box_wall(box, face, kWallColors[face]),
                                    centre + Vec3d{0.37 * face, -0.21, 0.13}));
}

// Unlit: these tests check geometry and exact vertex colours; the light model
// is tested in test_shading.cpp.
std::unique_ptr<ChunkRenderer> make_renderer(ChunkRendererParams params = {}) {
  auto renderer = std::make_unique<ChunkRenderer>(create_gl_context(GlBackend::osmesa, 1, 1), params);
  ShadingParams unlit;
  unlit.mode = ShadingMode::unlit;
  renderer->set_shading(shading_lights(unlit, Vec3d{0, 0, 1}));
  return renderer;
}

SampleParams small_params(int face_size = 32, int supersample = 1) {
  SampleParams p;
  p.face_size = face_size;
  p.supersample = supersample;
  return p;
}

std::size_t pixel(int size, int col, int row) { return static_cast<std::size_t>(row) * size + col; }

void expect_closed_box_seen(const CubeSample& sample, double tolerance) {
  for (int face = 0; face < kCubeFaces; ++face) {
    const CubeFace& f = sample.faces[face];
    ASSERT_EQ(f.depth.size(), static_cast<std::size_t>(f.size) * f.size);
    ASSERT_EQ(f.color.size(), f.depth.size());
    // Every pixel sees the wall square-on, so the planar depth is 1 everywhere.
    for (std::size_t i = 0; i < f.depth.size(); ++i) {
      ASSERT_NEAR(f.depth[i], 1.0, tolerance) << "face " << face << " pixel " << i;
      ASSERT_EQ(f.color[i], kWallColors[face]) << "face " << face << " pixel " << i;
    }
  }
}

TEST(Sample, ClosedBoxHasDepthOneOnEveryFaceAndTheWallColours) {
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  auto renderer = make_renderer();
  const CubeSample sample = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(), source, *renderer);
  EXPECT_EQ(sample.eye, (Vec3d{0, 0, 0}));
  for (const CubeFace& f : sample.faces) EXPECT_EQ(f.size, 32);
  expect_closed_box_seen(sample, 1e-4);
  // The four pixels around each face centre, named explicitly.
  for (int face = 0; face < kCubeFaces; ++face)
    for (int c : {15, 16})
      for (int r : {15, 16}) EXPECT_NEAR(sample.faces[face].depth[pixel(32, c, r)], 1.0, 1e-4);
}

TEST(Sample, FarFromTheWorldOriginDepthsKeepTheirPrecision) {
  // The second offset is not representable in float32 (ulp 0.25 m at 2e6 m):
  // only eye-relative coordinates computed in double keep depth 1 to 1e-4.
  for (const Vec3d offset : {Vec3d{1e6, -2e6, 5e5}, Vec3d{1e6 + 0.3137, -2e6 - 0.7071, 5e5 + 0.1234}}) {
    InMemoryChunkSource source;
    add_closed_box(source, offset);
    auto renderer = make_renderer();
    const CubeSample sample = sample_cube(offset, Box3d::cube(offset, 0.1), small_params(), source, *renderer);
    expect_closed_box_seen(sample, 1e-4);
  }
}

TEST(Sample, OrientationFollowsCubeMapConvention) {
  // A small marker just off the +X face centre, on the +up (+z) and +right (-y) side:
  // it must land in the upper-right quadrant of face 0 (row 0 at the top).
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  const Rgba8 marker{10, 20, 30, 255};
  source.add(chunk_from_triangles(
      10, {flat_triangle({0.9, -0.3, 0.3}, {0.9, -0.6, 0.3}, {0.9, -0.45, 0.6}, marker)}));
  auto renderer = make_renderer();
  const CubeSample sample = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(), source, *renderer);
  const CubeFace& f = sample.faces[0];
  int upper_right = 0, elsewhere = 0;
  for (int row = 0; row < f.size; ++row)
    for (int col = 0; col < f.size; ++col)
      if (f.color[pixel(f.size, col, row)] == marker) (row < f.size / 2 && col >= f.size / 2 ? upper_right : elsewhere)++;
  EXPECT_GT(upper_right, 4);
  EXPECT_EQ(elsewhere, 0);
  // Pixel centre direction (s, t) times the depth lands on the marker plane x = 0.9.
  for (int row = 0; row < f.size; ++row)
    for (int col = 0; col < f.size; ++col)
      if (f.color[pixel(f.size, col, row)] == marker) {
        const double s = 2.0 * (col + 0.5) / f.size - 1, t = 1 - 2.0 * (row + 0.5) / f.size;
        const Vec3d p = cube_face_direction(cube_face_basis(0), s, t) * f.depth[pixel(f.size, col, row)];
        EXPECT_NEAR(p.x, 0.9, 1e-4);
        EXPECT_LT(p.y, 0);
        EXPECT_GT(p.z, 0);
      }
}

// A small triangle at x = 0.5 covering the +X face centre.
Chunk blocker_chunk(std::int64_t id, Rgba8 color) {
  return chunk_from_triangles(id, {flat_triangle({0.5, -0.2, -0.2}, {0.5, 0.2, -0.2}, {0.5, 0.0, 0.3}, color)});
}

TEST(Sample, GeometryInsideTheCullBoxIsNotDrawn) {
  const Rgba8 blocker_color{1, 2, 3, 255};
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  source.add(blocker_chunk(20, blocker_color));
  const std::size_t centre = pixel(32, 16, 16);

  auto renderer = make_renderer();
  const CubeSample hidden = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.75), small_params(), source, *renderer);
  EXPECT_NEAR(hidden.faces[0].depth[centre], 1.0, 1e-4);
  EXPECT_EQ(hidden.faces[0].color[centre], kWallColors[0]);
  const auto loads = source.loads();
  EXPECT_EQ(std::count(loads.begin(), loads.end(), 20), 0) << "a chunk inside the cull box was loaded";

  const CubeSample seen = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.25), small_params(), source, *renderer);
  EXPECT_NEAR(seen.faces[0].depth[centre], 0.5, 1e-4);
  EXPECT_EQ(seen.faces[0].color[centre], blocker_color);
}

TEST(Sample, OffCentreEyeDiscardsPerFragment) {
  // A quad at x = 0.5 reaching out of the cull box: the eye sits off the box
  // centre, the quad's middle is inside the box and in front of the eye, so
  // only a per-fragment test (not a clip plane or a chunk test) hides it.
  const Rgba8 blocker_color{1, 2, 3, 255};
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  const double e = 0.95;
  source.add(chunk_from_triangles(20, {flat_triangle({0.5, -e, -e}, {0.5, e, -e}, {0.5, e, e}, blocker_color),
                                       flat_triangle({0.5, -e, -e}, {0.5, e, e}, {0.5, -e, e}, blocker_color)}));
  auto renderer = make_renderer();
  const Vec3d eye{0.3, 0, 0};
  const CubeSample s = sample_cube(eye, Box3d::cube({0, 0, 0}, 0.6), small_params(), source, *renderer);
  const std::size_t centre = pixel(32, 16, 16);
  EXPECT_NEAR(s.faces[0].depth[centre], 0.7, 1e-4);
  EXPECT_EQ(s.faces[0].color[centre], kWallColors[0]);
  EXPECT_EQ(std::count(s.faces[0].color.begin(), s.faces[0].color.end(), blocker_color), 0);
  // Looking back (-X) the wall at x = -1 is 1.3 away.
  EXPECT_NEAR(s.faces[1].depth[centre], 1.3, 1e-4);
  // The quad's rim outside the box (|y| > 0.6) is seen from the +Y face, at planar depth y.
  const CubeFace& plus_y = s.faces[2];
  int rim = 0;
  for (int row = 0; row < plus_y.size; ++row)
    for (int col = 0; col < plus_y.size; ++col)
      if (plus_y.color[pixel(32, col, row)] == blocker_color) {
        ++rim;
        const double sc = 2.0 * (col + 0.5) / 32 - 1;  // right = +x: x - 0.3 = sc * depth = 0.2
        EXPECT_NEAR(sc * plus_y.depth[pixel(32, col, row)], 0.2, 1e-4);
        EXPECT_GT(plus_y.depth[pixel(32, col, row)], 0.6 - 1e-4);
      }
  EXPECT_GT(rim, 4);
}

TEST(Sample, BackgroundIsInfinityWhereNothingIsDrawn) {
  InMemoryChunkSource source;
  source.add(chunk_from_triangles(1, box_wall(Box3d::cube({0, 0, 0}, 1.0), 0, kWallColors[0])));
  auto renderer = make_renderer();
  const CubeSample s = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(), source, *renderer);
  for (float d : s.faces[0].depth) ASSERT_NEAR(d, 1.0, 1e-4);
  for (int face = 1; face < kCubeFaces; ++face) {
    for (float d : s.faces[face].depth) ASSERT_EQ(d, kBackgroundDepth) << "face " << face;
    for (Rgba8 c : s.faces[face].color) ASSERT_EQ(c, (Rgba8{0, 0, 0, 0})) << "face " << face;
  }
}

TEST(Sample, PerFaceFrustumCullingLoadsOnlyNeededChunks) {
  const Rgba8 grey{128, 128, 128, 255};
  const auto tiny_at = [&](std::int64_t id, Vec3d c) {
    return chunk_from_triangles(id, {flat_triangle(c + Vec3d{0, -0.1, -0.1}, c + Vec3d{0, 0.1, -0.1},
                                                   c + Vec3d{0, 0, 0.1}, grey)});
  };
  InMemoryChunkSource source;
  source.add(tiny_at(1, {5, 0, 0}));     // +X only
  source.add(tiny_at(2, {20, 0, 0}));    // +X only; stretches face 0's query box over chunk 3
  source.add(tiny_at(3, {5, 8, 0}));     // +Y only: in face 0's query box, outside its frustum
  source.add(tiny_at(4, {0.3, 0, 0}));   // strictly inside the cull box
  source.add(tiny_at(5, {0, 0.5, -5}));  // -Z only
  const Box3d cull_box = Box3d::cube({0, 0, 0}, 1.0);
  const auto ids_of = [&](int face) {
    std::vector<std::int64_t> ids;
    for (const ChunkRef& r : chunks_in_face(face, {0, 0, 0}, cull_box, 0.01, source)) ids.push_back(r.id);
    return ids;
  };
  EXPECT_EQ(ids_of(0), (std::vector<std::int64_t>{1, 2}));
  EXPECT_EQ(ids_of(1), (std::vector<std::int64_t>{}));
  EXPECT_EQ(ids_of(2), (std::vector<std::int64_t>{3}));
  EXPECT_EQ(ids_of(3), (std::vector<std::int64_t>{}));
  EXPECT_EQ(ids_of(4), (std::vector<std::int64_t>{}));
  EXPECT_EQ(ids_of(5), (std::vector<std::int64_t>{5}));

  auto renderer = make_renderer();
  sample_cube({0, 0, 0}, cull_box, small_params(), source, *renderer);
  std::vector<std::int64_t> loads = source.loads();
  std::sort(loads.begin(), loads.end());
  EXPECT_EQ(loads, (std::vector<std::int64_t>{1, 2, 3, 5}));  // each needed chunk once, chunk 4 never

  // The renderer keeps them: a second sample from the same place loads nothing.
  source.clear_loads();
  sample_cube({0, 0, 0}, cull_box, small_params(), source, *renderer);
  EXPECT_TRUE(source.loads().empty());
}

// Face 0 (+X) of a scene with a big wall at x = 3: 40 chunks of random
// triangles in front of it and 200 behind it, all within face 0's frustum.
// Occlusion culling must draw exactly what drawing everything draws, and never
// load the hidden chunks.
TEST(Sample, OcclusionCullingSkipsHiddenChunksWithoutChangingTheImage) {
  InMemoryChunkSource source;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto random_chunk = [&](std::int64_t id, double x_lo, double x_hi, double lateral) {
    std::vector<Triangle> triangles;
    const Vec3d centre{x_lo + (x_hi - x_lo) * unit(rng), lateral * (2 * unit(rng) - 1), lateral * (2 * unit(rng) - 1)};
    const Rgba8 color{static_cast<std::uint8_t>(rng() % 256), static_cast<std::uint8_t>(rng() % 256), 200, 255};
    for (int t = 0; t < 20; ++t) {
      const auto jitter = [&] { return Vec3d{0.3 * unit(rng), 0.3 * unit(rng), 0.3 * unit(rng)}; };
      triangles.push_back(flat_triangle(centre + jitter(), centre + jitter(), centre + jitter(), color));
    }
    source.add(chunk_from_triangles(id, triangles));
  };
  for (std::int64_t id = 1; id <= 200; ++id) random_chunk(id, 4.0, 14.0, 3.0);  // hidden
  for (std::int64_t id = 201; id <= 240; ++id) random_chunk(id, 1.5, 2.5, 1.0);  // visible
  source.add(chunk_from_triangles(241, box_wall(Box3d{{-3, -10, -10}, {3, 10, 10}}, 0, Rgba8{90, 90, 90, 255})));

  const Vec3d eye{0, 0.01, -0.02};
  const Box3d cull_box = Box3d::cube(eye, 0.5);
  auto culling = make_renderer();
  if (!culling->occlusion_culling()) GTEST_SKIP() << "the GL context lacks GL 4.3";
  const CubeSample sample = sample_cube(eye, cull_box, small_params(96), source, *culling);
  // The 41 nearest chunks and the 23 nearest hidden ones make the first batch,
  // drawn untested; every later hidden chunk is tested against the wall.
  EXPECT_GE(culling->stats().chunks_occluded, 170u);
  std::size_t hidden_loaded = 0;
  for (std::int64_t id : source.loads()) hidden_loaded += id <= 200 ? 1 : 0;
  EXPECT_LE(hidden_loaded, 30u);

  // Reference: every chunk of face 0 drawn in id order, nothing skipped.
  auto plain = make_renderer();
  std::vector<std::int64_t> ids;
  for (const ChunkRef& r : chunks_in_face(0, eye, cull_box, 0.01, source)) ids.push_back(r.id);
  ASSERT_EQ(ids.size(), 241u);
  const RenderCamera camera = cube_face_camera(eye, 0);
  plain->begin_frame(96, 96);
  plain->draw(camera, cull_box, ids, [&](std::int64_t id) { return source.load(id); });
  std::vector<Rgba8> color;
  std::vector<float> depth;
  plain->read_frame(color, depth);
  EXPECT_EQ(sample.faces[0].color, color);
  EXPECT_EQ(sample.faces[0].depth, depth);
}

TEST(Sample, ChunkSharedByFacesIsLoadedOnce) {
  InMemoryChunkSource source;
  // One chunk holding all six walls: every face needs it.
  std::vector<Triangle> all;
  for (int face = 0; face < kCubeFaces; ++face)
    for (const Triangle& t : box_wall(Box3d::cube({0, 0, 0}, 1.0), face, kWallColors[face])) all.push_back(t);
  source.add(chunk_from_triangles(7, all));
  auto renderer = make_renderer();
  const CubeSample s = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(), source, *renderer);
  expect_closed_box_seen(s, 1e-4);
  EXPECT_EQ(source.loads(), (std::vector<std::int64_t>{7}));
}

TEST(Sample, SupersampleGivesTheSameDepthsOnAFlatWall) {
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  auto renderer = make_renderer();
  const CubeSample s = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(32, 2), source, *renderer);
  for (const CubeFace& f : s.faces) EXPECT_EQ(f.size, 32);
  expect_closed_box_seen(s, 1e-4);
}

TEST(Sample, SupersampledDepthOfASlantedPlaneIsThePixelCentreDepth) {
  // Plane x - 0.3 y = 1 seen by face 0 (right = -y, up = +z): the point at
  // face coordinates (s, t) is d (1, -s, t), so d = 1 / (1 + 0.3 s).
  const Rgba8 grey{90, 90, 90, 255};
  const auto on_plane = [](double y, double z) { return Vec3d{1 + 0.3 * y, y, z}; };
  InMemoryChunkSource source;
  source.add(chunk_from_triangles(1, {flat_triangle(on_plane(-5, -5), on_plane(5, -5), on_plane(5, 5), grey),
                                      flat_triangle(on_plane(-5, -5), on_plane(5, 5), on_plane(-5, 5), grey)}));
  auto renderer = make_renderer();
  for (int supersample : {1, 2, 3}) {
    const CubeSample s =
        sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(32, supersample), source, *renderer);
    const CubeFace& f = s.faces[0];
    for (int row = 0; row < f.size; ++row)
      for (int col = 0; col < f.size; ++col) {
        const double sc = 2.0 * (col + 0.5) / f.size - 1;
        ASSERT_NEAR(f.depth[pixel(f.size, col, row)], 1 / (1 + 0.3 * sc), 1e-4)
            << "supersample " << supersample << " col " << col << " row " << row;
        ASSERT_EQ(f.color[pixel(f.size, col, row)], grey);
      }
  }
}

TEST(Sample, DownsampleAveragesCoveredColourAndKeepsTheNearestDepthAcrossEdges) {
  const float inf = kBackgroundDepth;
  // All four subpixels covered by two surfaces (depths 1 and 10): the nearest.
  const CubeFace edge = downsample_face({{100, 0, 0, 255}, {200, 0, 0, 255}, {100, 0, 0, 255}, {200, 0, 0, 255}},
                                        {1, 10, 1, 10}, 1, 2, 0.05);
  EXPECT_EQ(edge.color[0], (Rgba8{150, 0, 0, 255}));
  EXPECT_EQ(edge.depth[0], 1.0f);
  // One covered subpixel: its colour and depth.
  const CubeFace rim = downsample_face({{0, 0, 0, 0}, {0, 50, 0, 255}, {0, 0, 0, 0}, {0, 0, 0, 0}},
                                       {inf, 4, inf, inf}, 1, 2, 0.05);
  EXPECT_EQ(rim.color[0], (Rgba8{0, 50, 0, 255}));
  EXPECT_EQ(rim.depth[0], 4.0f);
  // All four on one surface: harmonic mean, 1 / mean(1/2, 1/2, 1/2.02, 1/2.02).
  const CubeFace plane = downsample_face(std::vector<Rgba8>(4, Rgba8{}), {2.0f, 2.0f, 2.02f, 2.02f}, 1, 2, 0.05);
  EXPECT_NEAR(plane.depth[0], 4.0 / (2 / 2.0 + 2 / 2.02), 1e-6);
  // Nothing covered: background.
  const CubeFace empty = downsample_face(std::vector<Rgba8>(4, Rgba8{0, 0, 0, 0}), std::vector<float>(4, inf), 1, 2, 0.05);
  EXPECT_EQ(empty.depth[0], kBackgroundDepth);
  EXPECT_EQ(empty.color[0], (Rgba8{0, 0, 0, 0}));
}

TEST(ChunkRenderer, CacheCapEvictsAndResultsStayCorrect) {
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  // Each wall chunk is 6 vertices * 16 bytes + 6 16-bit indices = 108 bytes.
  ChunkRendererParams params;
  params.cache_bytes = 250;
  auto renderer = make_renderer(params);
  const CubeSample s = sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(), source, *renderer);
  expect_closed_box_seen(s, 1e-4);
  // Walls touching a face's frustum edge are drawn there too, so chunks are
  // re-uploaded as they are evicted; the cap holds throughout.
  const ChunkRendererStats stats = renderer->stats();
  EXPECT_GE(stats.uploads, 6u);
  EXPECT_GT(stats.evictions, 0u);
  EXPECT_EQ(stats.cached_chunks, 2u);
  EXPECT_LE(stats.cached_bytes, params.cache_bytes);
}

TEST(ChunkRenderer, MalformedChunkIsRejectedWithItsId) {
  InMemoryChunkSource source;
  Chunk bad = chunk_from_triangles(42, {flat_triangle({2, 0, 0}, {2, 1, 0}, {2, 0, 1}, Rgba8{})});
  bad.indices[1] = 99;
  source.add(bad);
  auto renderer = make_renderer();
  try {
    sample_cube({0, 0, 0}, Box3d{}, small_params(), source, *renderer);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("chunk 42"), std::string::npos) << e.what();
  }
}

TEST(ChunkRenderer, OneContextPerThreadGivesIdenticalResults) {
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  source.add(blocker_chunk(20, Rgba8{1, 2, 3, 255}));
  const Box3d cull_box = Box3d::cube({0, 0, 0}, 0.25);
  auto reference_renderer = make_renderer();
  const CubeSample reference = sample_cube({0.1, 0.05, 0}, cull_box, small_params(), source, *reference_renderer);
  std::array<CubeSample, 2> results;
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t)
    threads.emplace_back([&, t] {
      auto renderer = make_renderer();
      for (int repeat = 0; repeat < 3; ++repeat)
        results[t] = sample_cube({0.1, 0.05, 0}, cull_box, small_params(), source, *renderer);
    });
  for (auto& th : threads) th.join();
  for (const CubeSample& r : results)
    for (int face = 0; face < kCubeFaces; ++face) {
      EXPECT_EQ(r.faces[face].depth, reference.faces[face].depth) << "face " << face;
      EXPECT_EQ(r.faces[face].color, reference.faces[face].color) << "face " << face;
    }
}

// Face 0 (+X) from the origin sees (s, t) = (-y / x, z / x). Chunk 1, a wall
// at x = 5 over the face's left half, hides chunk 2's triangle 0 (x = 10);
// chunk 2's triangles 1 (tiles 6, 7, 10, 11) and 2 (tile 3 alone) are seen.
// Chunk 2's materials make the renderer draw its triangles in another order
// (grouped by material); chunk 3's triangle 1, a floor, crosses the near
// plane, so the rasteriser clips it into pieces; its triangle 0 lies behind
// the eye. Chunk 2's box is visible, so a list of drawn chunks would hold it
// whole; the primitive ids name the triangles that drew pixels.
TEST(Sample, SeenListsTheTrianglesThatDrewPixelsWithTheirTiles) {
  InMemoryChunkSource source;
  const Rgba8 grey{128, 128, 128, 255};
  source.add(chunk_from_triangles(1, {flat_triangle({5, 0, -6}, {5, 6, -6}, {5, 6, 6}, grey),
                                      flat_triangle({5, 0, -6}, {5, 6, 6}, {5, 0, 6}, grey)}));
  Chunk behind = chunk_from_triangles(2, {flat_triangle({10, 2, -3}, {10, 8, -3}, {10, 5, 3}, grey),
                                          flat_triangle({10, -2, -3}, {10, -8, -3}, {10, -5, 3}, grey),
                                          flat_triangle({10, -6, 6}, {10, -9, 6}, {10, -6, 9}, grey)});
  behind.materials = {1, 0, 0};  // drawn as triangles 1, 2, 0
  source.add(std::move(behind));
  source.add(chunk_from_triangles(3, {flat_triangle({-9, -1, -8}, {-6, -1, -8}, {-6, -3, -8}, grey),
                                      flat_triangle({-3, -1, -8}, {20, -1, -8}, {20, -20, -8}, grey)}));
  auto renderer = make_renderer();
  for (int supersample : {1, 2}) {
    const CubeSample sample =
        sample_cube({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.1), small_params(32, supersample), source, *renderer);
    const std::vector<SeenChunk>& seen = sample.faces[0].seen;
    ASSERT_EQ(seen.size(), 3u) << "supersample " << supersample;
    EXPECT_EQ(seen[0].id, 1);
    EXPECT_EQ(seen[0].triangles, (std::vector<std::uint32_t>{0, 1}));
    EXPECT_EQ(seen[0].tiles, 0x3333u) << "the face's left half";
    EXPECT_EQ(seen[1].id, 2);
    EXPECT_EQ(seen[1].triangles, (std::vector<std::uint32_t>{1, 2})) << "triangle 0 is hidden";
    EXPECT_EQ(seen[1].triangle_tiles, (std::vector<std::uint16_t>{0x0CC0, 0x0008}));
    EXPECT_EQ(seen[1].tiles, 0x0CC8u);
    EXPECT_EQ(seen[2].id, 3);
    EXPECT_EQ(seen[2].triangles, (std::vector<std::uint32_t>{1}));
    ASSERT_EQ(seen[2].triangle_tiles.size(), 1u);
    EXPECT_EQ(seen[2].triangle_tiles[0] & ~0xCC00u, 0u) << "the floor shows in the bottom right only";
    EXPECT_EQ(seen[2].triangle_tiles[0] & 0xC000u, 0xC000u);
    // Every seen triangle of every face drew a pixel of that face: its tiles are those of covered pixels.
    for (const CubeFace& f : sample.faces) {
      std::uint32_t covered = 0;
      for (int row = 0; row < f.size; ++row)
        for (int col = 0; col < f.size; ++col)
          if (std::isfinite(f.depth[pixel(f.size, col, row)])) covered |= 1u << pixel_tile(col, row, f.size);
      for (const SeenChunk& c : f.seen) {
        EXPECT_FALSE(c.whole());
        EXPECT_TRUE(std::is_sorted(c.triangles.begin(), c.triangles.end()));
        EXPECT_EQ(c.tiles & ~covered, 0u);
      }
    }
  }
}

// The primitive-id attachment changes no colour or depth bit; a frame begun
// without it cannot be asked for ids.
TEST(ChunkRenderer, PrimitiveIdsChangeNoPixel) {
  InMemoryChunkSource source;
  add_closed_box(source, {0, 0, 0});
  source.add(blocker_chunk(10, {10, 20, 30, 255}));
  auto renderer = make_renderer();
  const auto load = [&](std::int64_t id) { return source.load(id); };
  const std::vector<std::int64_t> ids = {10, 1, 2, 3, 4, 5, 6};
  std::vector<Rgba8> color[2];
  std::vector<float> depth[2];
  std::vector<std::int64_t> chunk;
  std::vector<std::uint32_t> triangle;
  for (int pass = 0; pass < 3; ++pass) {  // without, with, without again
    const bool with_ids = pass == 1;
    renderer->begin_frame(48, 40, with_ids);
    renderer->draw(cube_face_camera({0, 0, 0}, 0), Box3d::cube({0, 0, 0}, 0.1), ids, load);
    renderer->read_frame(color[with_ids], depth[with_ids]);
    if (with_ids) {
      renderer->read_primitive_ids(chunk, triangle);
      ASSERT_EQ(chunk.size(), std::size_t{48 * 40});
      for (std::size_t i = 0; i < chunk.size(); ++i) {
        EXPECT_EQ(chunk[i] == 10, color[1][i] == (Rgba8{10, 20, 30, 255})) << "pixel " << i;
        EXPECT_TRUE(chunk[i] == 10 || chunk[i] == 1) << "pixel " << i;  // the blocker or the +X wall
      }
    } else {
      EXPECT_THROW(renderer->read_primitive_ids(chunk, triangle), std::logic_error);
    }
    if (pass == 2) {
      EXPECT_EQ(color[0], color[1]);
      EXPECT_EQ(depth[0].size(), depth[1].size());
      EXPECT_EQ(std::memcmp(depth[0].data(), depth[1].data(), depth[0].size() * sizeof(float)), 0);
    }
  }
}

TEST(Sample, RejectsBadParameters) {
  InMemoryChunkSource source;
  auto renderer = make_renderer();
  SampleParams p = small_params();
  p.face_size = 0;
  EXPECT_THROW(sample_cube({0, 0, 0}, Box3d{}, p, source, *renderer), std::invalid_argument);
  p = small_params();
  p.supersample = 0;
  EXPECT_THROW(sample_cube({0, 0, 0}, Box3d{}, p, source, *renderer), std::invalid_argument);
  p = small_params();
  p.near_plane = 0;
  EXPECT_THROW(sample_cube({0, 0, 0}, Box3d{}, p, source, *renderer), std::invalid_argument);
  EXPECT_THROW(sample_cube({NAN, 0, 0}, Box3d{}, small_params(), source, *renderer), std::invalid_argument);
}

}  // namespace
}  // namespace cellbake
