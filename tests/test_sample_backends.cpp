// Parity of the sampling backends (issue #12): the Embree ray caster against
// the OSMesa rasteriser on the same cube maps, and the pieces of the ray
// caster (ray segments, BVH cache) on their own.
//
// Tolerance (stated in issue #12), per cube map, over all six faces:
//  * coverage (finite depth) differs on at most 0.1 % of pixels — pixel-centre
//    rays and rasterisation rules disagree only on triangle edges;
//  * on at least 99.9 % of the pixels both cover, planar depth agrees within
//    1e-4 relative;
//  * colour PSNR over the pixels both cover (R, G, B, A; peak 255) >= 40 dB.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <thread>

#include "pipeline/sample_backend.h"
#include "pipeline/scenes/scene_generator.h"
#include "stages/chunking.h"
#include "stages/cull_box.h"
#include "stages/raycast/chunk_bvh_cache.h"
#include "stages/raycast/embree_cube_sampler.h"
#include "stages/raycast/ray_segments.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_context_egl.h"
#include "stages/render/gl_cube_sampler.h"
#include "stages/sample/sample.h"
#include "tests/fixture_chunk_source.h"

namespace cellbake {
namespace {

using test::chunk_from_triangles;
using test::flat_triangle;
using test::InMemoryChunkSource;

constexpr double kMaxCoverageMismatch = 0.001;
constexpr double kDepthRelative = 1e-4;
constexpr double kMinDepthAgreeing = 0.999;
constexpr double kMinPsnr = 40.0;

struct Parity {
  std::size_t pixels = 0, both = 0, coverage_mismatch = 0, depth_agreeing = 0;
  double squared_error = 0;  // colour, summed over channels of pixels both cover
  double coverage_mismatch_fraction() const { return double(coverage_mismatch) / double(pixels); }
  double depth_agreeing_fraction() const { return both ? double(depth_agreeing) / double(both) : 1.0; }
  double psnr() const {
    if (both == 0 || squared_error == 0) return std::numeric_limits<double>::infinity();
    return 10 * std::log10(255.0 * 255.0 / (squared_error / double(4 * both)));
  }
};

Parity compare(const CubeSample& a, const CubeSample& b) {
  Parity p;
  for (int f = 0; f < kCubeFaces; ++f) {
    const CubeFace &fa = a.faces[std::size_t(f)], &fb = b.faces[std::size_t(f)];
    EXPECT_EQ(fa.size, fb.size);
    for (std::size_t i = 0; i < fa.depth.size(); ++i) {
      ++p.pixels;
      const bool ca = std::isfinite(fa.depth[i]), cb = std::isfinite(fb.depth[i]);
      if (ca != cb) ++p.coverage_mismatch;
      if (!ca || !cb) continue;
      ++p.both;
      const double da = fa.depth[i], db = fb.depth[i];
      if (std::abs(da - db) <= kDepthRelative * std::max(da, db)) ++p.depth_agreeing;
      const Rgba8 x = fa.color[i], y = fb.color[i];
      for (double d : {double(x.r) - y.r, double(x.g) - y.g, double(x.b) - y.b, double(x.a) - y.a})
        p.squared_error += d * d;
    }
  }
  return p;
}

void expect_parity(const CubeSample& gl, const CubeSample& rays, const char* what) {
  const Parity p = compare(gl, rays);
  EXPECT_LE(p.coverage_mismatch_fraction(), kMaxCoverageMismatch) << what;
  EXPECT_GE(p.depth_agreeing_fraction(), kMinDepthAgreeing) << what;
  EXPECT_GE(p.psnr(), kMinPsnr) << what;
  EXPECT_GT(p.both, 0u) << what;
  std::printf("%s: %zu px, coverage mismatch %.5f %%, depth within 1e-4 on %.4f %%, PSNR %.2f dB\n", what, p.pixels,
              100 * p.coverage_mismatch_fraction(), 100 * p.depth_agreeing_fraction(), p.psnr());
}

ShadingLights default_lights() { return shading_lights(ShadingParams{}, Vec3d{0, 0, 1}); }

// Seen-triangle parity (issue #35): both backends list the triangles that
// drew pixels (CubeFace::seen). Pixel-centre rays and rasterisation rules
// disagree only on pixels at triangle edges (ties), so a triangle one backend
// lists and the other does not owns only such pixels: per cube map, the GL
// pixels of triangles only GL lists, plus the triangles only the ray caster
// lists (each owns at least one of its pixels), stay within the coverage
// tolerance. Every triangle GL lists drew a pixel of the face (checked
// against a frame of the same chunks drawn with primitive ids), and on the
// triangles both list the tile masks agree but for tie pixels on tile borders.
constexpr double kMaxSeenTiePixels = 0.002;
constexpr double kMinSameTiles = 0.99;

using SeenTriangle = std::pair<std::int64_t, std::uint32_t>;

std::map<SeenTriangle, std::uint16_t> seen_set(const CubeFace& face) {
  std::map<SeenTriangle, std::uint16_t> set;
  for (const SeenChunk& c : face.seen) {
    EXPECT_FALSE(c.whole()) << "chunk " << c.id << " listed whole";
    EXPECT_TRUE(std::is_sorted(c.triangles.begin(), c.triangles.end()));
    EXPECT_EQ(c.triangles.size(), c.triangle_tiles.size());
    std::uint32_t tiles = 0;
    for (std::size_t k = 0; k < c.triangles.size(); ++k) {
      set[{c.id, c.triangles[k]}] = c.triangle_tiles[k];
      tiles |= c.triangle_tiles[k];
    }
    EXPECT_EQ(tiles, c.tiles) << "chunk " << c.id;
  }
  return set;
}

// The (chunk, triangle) of each pixel of face `face` of the GL sample: the
// chunks chunks_in_face() lists drawn with primitive ids.
std::vector<SeenTriangle> gl_pixel_triangles(ChunkRenderer& renderer, int face, const Vec3d& eye,
                                             const Box3d& cull_box, const SampleParams& params,
                                             const ChunkSource& source) {
  const int size = params.face_size * params.supersample;
  std::vector<std::int64_t> ids;
  for (const ChunkRef& c : chunks_in_face(face, eye, cull_box, params.near_plane, source))
    ids.push_back(c.id);
  renderer.use_materials_of(source);  // alpha-tested texels drop fragments here too
  renderer.begin_frame(size, size, true);
  renderer.draw(cube_face_camera(eye, face, params.near_plane), cull_box, ids,
                [&](std::int64_t id) { return source.load(id); });
  std::vector<std::int64_t> chunk;
  std::vector<std::uint32_t> triangle;
  renderer.read_primitive_ids(chunk, triangle);
  std::vector<SeenTriangle> pixels(chunk.size());
  for (std::size_t p = 0; p < chunk.size(); ++p) pixels[p] = {chunk[p], triangle[p]};
  return pixels;
}

void expect_seen_parity(ChunkRenderer& renderer, const CubeSample& gl, const CubeSample& rays,
                        const SampleParams& params, const Box3d& cull_box, const ChunkSource& source,
                        const char* what) {
  std::size_t pixels = 0, gl_only_pixels = 0, gl_only = 0, rays_only = 0, both = 0, same_tiles = 0;
  for (int f = 0; f < kCubeFaces; ++f) {
    const auto a = seen_set(gl.faces[std::size_t(f)]), b = seen_set(rays.faces[std::size_t(f)]);
    const std::vector<SeenTriangle> owner = gl_pixel_triangles(renderer, f, gl.eye, cull_box, params, source);
    pixels += owner.size();
    std::map<SeenTriangle, std::size_t> drew;
    for (const SeenTriangle& k : owner)
      if (k.first >= 0) ++drew[k];
    for (const auto& [key, tiles] : a) {
      EXPECT_TRUE(drew.contains(key)) << what << ": face " << f << " lists chunk " << key.first
                                      << " triangle " << key.second << ", which drew no pixel";
      const auto it = b.find(key);
      if (it == b.end()) {
        ++gl_only;
        gl_only_pixels += drew.contains(key) ? drew[key] : 0;
      } else {
        ++both;
        same_tiles += it->second == tiles;
      }
    }
    for (const auto& [key, tiles] : b) rays_only += !a.contains(key);
  }
  const double tie_fraction = double(gl_only_pixels + rays_only) / double(pixels);
  EXPECT_LE(tie_fraction, kMaxSeenTiePixels) << what;
  EXPECT_GE(double(same_tiles) / double(std::max<std::size_t>(both, 1)), kMinSameTiles) << what;
  EXPECT_GT(both, 0u) << what;
  std::printf(
      "%s: seen triangles %zu in both, %zu GL only (%zu px), %zu rays only; tie pixels %.4f %%, same "
      "tiles %.3f %%\n",
      what, both, gl_only, gl_only_pixels, rays_only, 100 * tie_fraction,
      100.0 * double(same_tiles) / double(std::max<std::size_t>(both, 1)));
}

struct Backends {
  GlCubeSampler gl{std::make_unique<ChunkRenderer>(create_gl_context(GlBackend::osmesa, 1, 1)), "osmesa"};
  ChunkRenderer ids{create_gl_context(GlBackend::osmesa, 1, 1)};  // the GL faces again, for seen parity
  std::shared_ptr<ChunkBvhCache> cache = std::make_shared<ChunkBvhCache>();
  EmbreeCubeSampler embree{cache};
  Backends() {
    gl.set_shading(default_lights());
    embree.set_shading(default_lights());
  }
  void check(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params, const ChunkSource& source,
             const char* what) {
    const CubeSample a = gl.sample(eye, cull_box, params, source);
    const CubeSample b = embree.sample(eye, cull_box, params, source);
    expect_parity(a, b, what);
    expect_seen_parity(ids, a, b, params, cull_box, source, what);
  }
};

SampleParams params(int face_size, int supersample = 1) {
  SampleParams p;
  p.face_size = face_size;
  p.supersample = supersample;
  return p;
}

Rgba8 random_color(std::mt19937_64& rng) {
  return {std::uint8_t(rng() % 256), std::uint8_t(rng() % 256), std::uint8_t(rng() % 256), 255};
}

// A room of side 20 around `centre` (two triangles per wall, one chunk per
// wall, one colour per corner so colours vary across walls), plus 300 random
// triangles with per-corner colours between 2 and 9 m from the centre, in
// chunks of 50: slanted surfaces, edges and occlusion everywhere.
std::unique_ptr<InMemoryChunkSource> room(const Vec3d& centre, std::uint64_t seed = 7) {
  auto owned = std::make_unique<InMemoryChunkSource>();
  InMemoryChunkSource& source = *owned;
  std::mt19937_64 rng(seed);
  const Box3d box = Box3d::cube(centre, 10.0);
  std::int64_t id = 1;
  for (int face = 0; face < kCubeFaces; ++face) {
    const int axis = face / 2, u = (axis + 1) % 3, v = (axis + 2) % 3;
    std::array<Vec3d, 4> q;
    const double us[4] = {box.lo[u], box.hi[u], box.hi[u], box.lo[u]};
    const double vs[4] = {box.lo[v], box.lo[v], box.hi[v], box.hi[v]};
    for (int i = 0; i < 4; ++i) {
      q[std::size_t(i)][axis] = face % 2 == 0 ? box.hi[axis] : box.lo[axis];
      q[std::size_t(i)][u] = us[i];
      q[std::size_t(i)][v] = vs[i];
    }
    Triangle a = flat_triangle(q[0], q[1], q[2], {}), b = flat_triangle(q[0], q[2], q[3], {});
    const std::array<Rgba8, 4> corner = {random_color(rng), random_color(rng), random_color(rng), random_color(rng)};
    a.color = {corner[0], corner[1], corner[2]};
    b.color = {corner[0], corner[2], corner[3]};
    source.add(chunk_from_triangles(id++, {a, b}, centre + Vec3d{0.37 * face, -0.21, 0.13}));
  }
  std::uniform_real_distribution<double> unit(-1.0, 1.0), radius(2.0, 9.0), edge(-1.5, 1.5);
  for (int c = 0; c < 6; ++c) {
    std::vector<Triangle> triangles;
    for (int t = 0; t < 50; ++t) {
      Vec3d d{unit(rng), unit(rng), unit(rng)};
      d = d * (radius(rng) / std::max(1e-3, length(d)));
      const Vec3d p = centre + d;
      Triangle tri = flat_triangle(p, p + Vec3d{edge(rng), edge(rng), edge(rng)},
                                   p + Vec3d{edge(rng), edge(rng), edge(rng)}, {});
      tri.color = {random_color(rng), random_color(rng), random_color(rng)};
      triangles.push_back(tri);
    }
    source.add(chunk_from_triangles(id++, triangles));
  }
  return owned;
}

TEST(RaySegments, EyeInsideStartsWhereTheRayLeavesTheBox) {
  const EyeBox box = eye_relative_box(Box3d::cube({0, 0, 0}, 2.0), {0.5, 0, 0});
  const RaySegments s = ray_segments({1, 0, 0}, box, 0.01);
  EXPECT_FALSE(s.two);
  EXPECT_NEAR(s.t0, 1.5, 1e-6);
  EXPECT_LE(s.t0, 1.5f);
  EXPECT_TRUE(std::isinf(s.t1));
}

TEST(RaySegments, EyeOutsideSkipsOnlyTheInterior) {
  const EyeBox box = eye_relative_box(Box3d{{2, -1, -1}, {4, 1, 1}}, {0, 0, 0});
  const RaySegments s = ray_segments({1, 0, 0}, box, 0.01);
  ASSERT_TRUE(s.two);
  EXPECT_FLOAT_EQ(s.t0, 0.01f);
  EXPECT_NEAR(s.t1, 2.0, 1e-6);
  EXPECT_GE(s.t1, 2.0f);
  EXPECT_NEAR(s.t2, 4.0, 1e-6);
  EXPECT_LE(s.t2, 4.0f);
  // A ray that misses the box, and one that grazes its face (not strictly inside): one segment.
  EXPECT_FALSE(ray_segments({1, 1, 0}, box, 0.01).two);
  EXPECT_FALSE(ray_segments({1, 0, 0}, eye_relative_box(Box3d{{2, 0, -1}, {4, 1, 1}}, {0, 0, 0}), 0.01).two);
  // Empty and flat boxes discard nothing.
  EXPECT_FALSE(ray_segments({1, 0, 0}, eye_relative_box(Box3d{}, {0, 0, 0}), 0.01).two);
  EXPECT_FLOAT_EQ(ray_segments({1, 0, 0}, eye_relative_box(Box3d{{-1, -1, 0}, {1, 1, 0}}, {0, 0, 0}), 0.5).t0, 0.5f);
}

TEST(RaySegments, BoxBehindTheNearPlaneIsIgnored) {
  const EyeBox box = eye_relative_box(Box3d{{-3, -1, -1}, {-2, 1, 1}}, {0, 0, 0});
  const RaySegments s = ray_segments({1, 0, 0}, box, 0.01);
  EXPECT_FALSE(s.two);
  EXPECT_FLOAT_EQ(s.t0, 0.01f);
}

// The sampler's segments come from per-face, per-column and per-row slabs:
// the same bits as the slab test per ray, on every face, for boxes around,
// beside and behind the eye, flat ones and none.
TEST(RaySegments, FaceSlabsGiveEachRaysOwnSegments) {
  const std::vector<std::pair<Box3d, Vec3d>> boxes = {
      {Box3d{{-0.7, -1.3, -0.4}, {2.1, 0.9, 1.6}}, {0.1, -0.2, 0.3}},  // eye inside
      {Box3d{{2, -1, -1}, {4, 1, 1}}, {0, 0, 0}},                      // ahead on +x
      {Box3d{{-3, -0.5, 0.2}, {-0.2, 0.5, 3}}, {0, 0, 0}},             // beside, off-axis
      {Box3d{{-1, -1, 0}, {1, 1, 0}}, {0, 0, 0}},                      // flat: none
      {Box3d{}, {0, 0, 0}}};                                           // empty: none
  for (const auto& [world, eye] : boxes) {
    const EyeBox box = eye_relative_box(world, eye);
    for (int size : {7, 64, 513}) {
      std::vector<double> coordinate(static_cast<std::size_t>(size)), inverse(coordinate.size());
      for (int i = 0; i < size; ++i) {
        coordinate[std::size_t(i)] = 2.0 * (i + 0.5) / size - 1.0;  // 0 in the middle of odd sizes
        inverse[std::size_t(i)] = 1.0 / coordinate[std::size_t(i)];
      }
      FaceSlabs slabs;
      for (int face = 0; face < kCubeFaces; ++face) {
        const FaceBasis b = cube_face_basis(face);
        slabs.set(b, box, coordinate, inverse);
        for (int col = 0; col < size; col += std::max(1, size / 37))
          for (int row = 0; row < size; row += std::max(1, size / 41)) {
            const Vec3d dir =
                cube_face_direction(b, coordinate[std::size_t(col)], -coordinate[std::size_t(row)]);
            const RaySegments a = slabs.segments(std::size_t(col), std::size_t(row), 0.01);
            const RaySegments d = ray_segments(dir, box, 0.01);
            ASSERT_EQ(a.t0, d.t0) << face << " " << col << " " << row;
            ASSERT_EQ(a.t1, d.t1);
            ASSERT_EQ(a.two, d.two);
            ASSERT_EQ(a.t2, d.t2);
          }
      }
    }
  }
}

TEST(BlockOrder, VisitsEveryPixelOnceInFourByFourBlocks) {
  for (int size : {1, 4, 7, 16}) {
    const std::vector<std::uint32_t> order = block_order(size);
    ASSERT_EQ(order.size(), std::size_t(size * size));
    std::vector<std::uint32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t i = 0; i < sorted.size(); ++i) EXPECT_EQ(sorted[i], i);
  }
  const std::vector<std::uint32_t> order = block_order(8);
  EXPECT_EQ(order[0], 0u);
  EXPECT_EQ(order[4], 8u);   // second row of the first block
  EXPECT_EQ(order[16], 4u);  // the second block starts at column 4
}

TEST(SampleBackends, RoomAroundTheEyeMatches) {
  Backends b;
  const auto owned = room({0, 0, 0});
  const InMemoryChunkSource& source = *owned;
  const Vec3d eye{0.3, -0.2, 0.1};
  b.check(eye, Box3d::cube({0, 0, 0}, 1.0), params(128), source, "room, centred eye");
  b.check(eye, Box3d::cube({0, 0, 0}, 1.0), params(64, 2), source, "room, supersampled 2x");
}

TEST(SampleBackends, UnlitColoursMatch) {
  Backends b;
  ShadingParams unlit;
  unlit.mode = ShadingMode::unlit;
  b.gl.set_shading(shading_lights(unlit, {0, 0, 1}));
  b.embree.set_shading(shading_lights(unlit, {0, 0, 1}));
  const auto owned = room({0, 0, 0}, 11);
  const InMemoryChunkSource& source = *owned;
  b.check({0, 0, 0}, Box3d::cube({0, 0, 0}, 1.0), params(96), source, "room, unlit");
}

TEST(SampleBackends, FarFromTheOriginMatches) {
  Backends b;
  const Vec3d centre{1.0e6 + 0.123, -2.0e6 + 0.456, 3.0e5 + 0.789};
  const auto owned = room(centre);
  const InMemoryChunkSource& source = *owned;
  b.check(centre + Vec3d{0.3, -0.2, 0.1}, Box3d::cube(centre, 1.0), params(128), source, "room at 1e6 m");
}

TEST(SampleBackends, OffCentreEyeAndEyeOutsideTheCullBoxMatch) {
  Backends b;
  const auto owned = room({0, 0, 0}, 3);
  const InMemoryChunkSource& source = *owned;
  // The eye near a corner of a large cull box that hides many of the random triangles.
  b.check({2.5, 2.0, -2.2}, Box3d::cube({0, 0, 0}, 3.0), params(128), source, "off-centre eye");
  // The eye outside the cull box: only what lies strictly inside the box disappears.
  b.check({-6, 0.5, 0.2}, Box3d{{-3, -3, -3}, {3, 3, 3}}, params(128), source, "eye outside the cull box");
}

TEST(SampleBackends, PerVertexNormalsMatch) {
  // The room with a random unit normal at every vertex: both backends light
  // with the normalised barycentric interpolation of the corner normals.
  const auto owned = room({0, 0, 0}, 13);
  InMemoryChunkSource source;
  std::mt19937_64 rng(17);
  std::normal_distribution<double> gauss;
  for (const ChunkRef& ref : owned->query(owned->model_bounds())) {
    Chunk c = *owned->load(ref.id);
    for (std::size_t v = 0; v < c.positions.size(); ++v) {
      Vec3d n{gauss(rng), gauss(rng), gauss(rng)};
      n = n * (1.0 / length(n));
      c.normals.push_back({float(n.x), float(n.y), float(n.z)});
    }
    source.add(std::move(c));
  }
  Backends b;
  b.check({0.3, -0.2, 0.1}, Box3d::cube({0, 0, 0}, 1.0), params(128), source, "room, per-vertex normals");
}

TEST(SampleBackends, EyeOutsideTheCullBoxHidesOnlyItsInterior) {
  // A wall at x = 5 behind the cull box [1, 3]^3-ish, and a wall at x = 2 inside it.
  InMemoryChunkSource source;
  const Rgba8 far_color{10, 200, 10, 255}, inside_color{200, 10, 10, 255};
  const auto wall = [](double x, Rgba8 c) {
    return std::vector<Triangle>{flat_triangle({x, -4, -4}, {x, 4, -4}, {x, 4, 4}, c),
                                 flat_triangle({x, -4, -4}, {x, 4, 4}, {x, -4, 4}, c)};
  };
  source.add(chunk_from_triangles(1, wall(5, far_color)));
  source.add(chunk_from_triangles(2, wall(2, inside_color)));
  EmbreeCubeSampler embree(std::make_shared<ChunkBvhCache>());
  ShadingParams unlit;
  unlit.mode = ShadingMode::unlit;
  embree.set_shading(shading_lights(unlit, {0, 0, 1}));
  const CubeSample s = embree.sample({0, 0, 0}, Box3d{{1, -1, -1}, {3, 1, 1}}, params(16), source);
  const CubeFace& px = s.faces[0];
  const std::size_t centre = std::size_t(8 * 16 + 8);
  EXPECT_NEAR(px.depth[centre], 5.0, 1e-5);  // through the box: the wall inside is gone
  EXPECT_EQ(px.color[centre], far_color);
  EXPECT_NEAR(px.depth[0], 2.0, 1e-5);       // past the box's side: the inner wall is seen
  EXPECT_EQ(px.color[0], inside_color);
}

TEST(SampleBackends, PerVertexNormalsAreInterpolatedAndTwoSided) {
  // One big triangle facing the eye, whose corner normals all point along n
  // (flipped on one corner pair's sign to check two-sidedness is per pixel).
  const Vec3d n = Vec3d{0.3, 0.5, 0.8} * (1.0 / length(Vec3d{0.3, 0.5, 0.8}));
  Chunk chunk = chunk_from_triangles(1, {flat_triangle({5, -50, -50}, {5, 50, -50}, {5, 0, 80}, {120, 60, 30, 255})});
  chunk.normals.assign(chunk.positions.size(), Vec3f{float(n.x), float(n.y), float(n.z)});
  InMemoryChunkSource source;
  source.add(chunk);
  EmbreeCubeSampler embree(std::make_shared<ChunkBvhCache>());
  const ShadingLights lights = default_lights();
  embree.set_shading(lights);
  const CubeSample s = embree.sample({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.5), params(16), source);
  const Rgba8 expected = apply_lighting({120, 60, 30, 255}, lighting_factor(lights, n));
  const Rgba8 got = s.faces[0].color[std::size_t(8 * 16 + 8)];
  EXPECT_NEAR(got.r, expected.r, 1);
  EXPECT_NEAR(got.g, expected.g, 1);
  EXPECT_NEAR(got.b, expected.b, 1);
  // The flat normal (+x) would give a different colour.
  const Rgba8 flat = apply_lighting({120, 60, 30, 255}, lighting_factor(lights, {1, 0, 0}));
  EXPECT_NE(expected, flat);
}

// A generated plant (~150 k triangles) chunked as ingest does, sampled at a
// cell centre with the cull box the cull_box stage finds for it.
std::unique_ptr<InMemoryChunkSource> generated_plant() {
  std::vector<Triangle> triangles;
  SceneParams sp;
  sp.kind = SceneKind::plant;
  sp.target_triangles = 150'000;
  sp.seed = 3;
  generate_scene(sp, [&](const TriangleMesh& part) {
    for (std::size_t i = 0; i < part.indices.size(); i += 3) {
      Triangle t;
      for (int k = 0; k < 3; ++k) {
        t.p[std::size_t(k)] = part.positions[part.indices[i + std::size_t(k)]];
        t.color[std::size_t(k)] = part.colors[part.indices[i + std::size_t(k)]];
      }
      if (!is_degenerate(t)) triangles.push_back(t);
    }
  });
  std::vector<TriangleKey> keys;
  keys.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) keys.push_back(make_triangle_key(triangles[i], std::uint32_t(i)));
  auto owned = std::make_unique<InMemoryChunkSource>();
  InMemoryChunkSource& source = *owned;
  std::int64_t id = 1;
  for (const ChunkRange& r : split_into_chunks(keys, 4096)) {
    std::vector<const Triangle*> chunk;
    for (std::size_t k = r.begin; k < r.end; ++k) chunk.push_back(&triangles[keys[k].index]);
    Chunk c = build_chunk(chunk);
    c.id = id++;
    source.add(std::move(c));
  }
  return owned;
}

TEST(SampleBackends, GeneratedPlantCellMatches) {
  const auto owned = generated_plant();
  const InMemoryChunkSource& source = *owned;
  const Box3d model = source.model_bounds();
  Backends b;
  for (const Vec3d& eye : {Vec3d{model.center().x, model.center().y, model.lo.z + 1.7},
                           Vec3d{model.lo.x + 0.3 * model.extent().x, model.center().y + 2.1, model.lo.z + 4.2}}) {
    CullBoxParams cp;
    cp.min_half_size = 2.0;
    cp.triangle_budget = 20'000;
    const Box3d cull = Box3d::cube(eye, find_cull_box(eye, cp, source).half_size);
    b.check(eye, cull, params(256), source, "generated plant cell");
  }
  EXPECT_EQ(b.cache->stats().builds, b.cache->stats().groups);
}

ChunkBvhCacheParams one_chunk_per_group(std::size_t cache_bytes = std::size_t{1} << 30) {
  ChunkBvhCacheParams p;
  p.group_triangles = 1;
  p.cache_bytes = cache_bytes;
  return p;
}

TEST(ChunkBvhCache, SharedBetweenThreadsBuildsEachGroupOnceAndGivesTheSamePixels) {
  const auto owned = room({0, 0, 0}, 5);
  const InMemoryChunkSource& source = *owned;
  auto cache = std::make_shared<ChunkBvhCache>(one_chunk_per_group());
  std::vector<CubeSample> results(4);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < results.size(); ++i)
    threads.emplace_back([&, i] {
      EmbreeCubeSampler sampler(cache);
      results[i] = sampler.sample({0.1, 0.2, 0.3}, Box3d::cube({0, 0, 0}, 1.0), params(32), source);
    });
  for (auto& t : threads) t.join();
  for (std::size_t i = 1; i < results.size(); ++i)
    for (int f = 0; f < kCubeFaces; ++f) {
      EXPECT_EQ(results[i].faces[std::size_t(f)].color, results[0].faces[std::size_t(f)].color);
      EXPECT_EQ(results[i].faces[std::size_t(f)].depth, results[0].faces[std::size_t(f)].depth);
    }
  const ChunkBvhCacheStats s = cache->stats();
  EXPECT_EQ(s.builds, source.query(source.model_bounds()).size());
  EXPECT_EQ(s.builds + s.hits, results.size() * source.query(source.model_bounds()).size());
}

TEST(ChunkBvhCache, ByteCapEvictsLeastRecentlyUsedChunksAndResultsStayTheSame) {
  const auto owned = room({0, 0, 0}, 9);
  const InMemoryChunkSource& source = *owned;
  // Nothing stays once a cube map is done under a 1-byte cap.
  auto capped = std::make_shared<ChunkBvhCache>(one_chunk_per_group(1));
  auto roomy = std::make_shared<ChunkBvhCache>(one_chunk_per_group());
  EmbreeCubeSampler a(capped), b(roomy);
  for (int pass = 0; pass < 2; ++pass) {
    const CubeSample x = a.sample({0, 0, 0}, Box3d::cube({0, 0, 0}, 1.0), params(16), source);
    const CubeSample y = b.sample({0, 0, 0}, Box3d::cube({0, 0, 0}, 1.0), params(16), source);
    for (int f = 0; f < kCubeFaces; ++f) EXPECT_EQ(x.faces[std::size_t(f)].depth, y.faces[std::size_t(f)].depth);
  }
  const std::size_t chunks = source.query(source.model_bounds()).size();
  EXPECT_EQ(capped->stats().builds, 2 * chunks);
  EXPECT_EQ(capped->stats().cached_groups, 0u);
  EXPECT_EQ(roomy->stats().builds, chunks);
  EXPECT_EQ(roomy->stats().cached_groups, chunks);
}

TEST(ChunkBvhCache, BeyondTheCapTheGroupsFarthestFromTheFocusGoFirst) {
  // Cube maps traced in batches visit their groups nearest first: the cache
  // keeps the groups nearest the latest eye, which the next cube map needs first.
  const auto owned = room({0, 0, 0}, 9);
  const InMemoryChunkSource& source = *owned;
  const std::vector<ChunkRef> refs = source.query(source.model_bounds());
  std::size_t all_bytes = 0;
  {
    ChunkBvhCache roomy(one_chunk_per_group());
    roomy.acquire(refs, source, true);
    all_bytes = roomy.stats().device_bytes + roomy.stats().chunk_bytes;
  }
  ChunkBvhCache cache(one_chunk_per_group(all_bytes / 2));
  const std::vector<ChunkGroupRefs> groups = cache.groups_of(refs, source);
  ASSERT_GE(groups.size(), 4u);
  const Vec3d focus = source.model_bounds().hi;
  cache.set_focus(focus);
  cache.acquire(refs, source, true);  // held while acquired, released here
  cache.trim();
  const std::size_t kept = cache.stats().cached_groups;
  ASSERT_GT(kept, 0u);
  ASSERT_LT(kept, groups.size());
  double nearest_dropped = std::numeric_limits<double>::infinity(), farthest_kept = 0;
  for (const ChunkGroupRefs& g : groups) {
    if (cache.holds(g.group, true)) farthest_kept = std::max(farthest_kept, g.bounds.distance_to(focus));
    else nearest_dropped = std::min(nearest_dropped, g.bounds.distance_to(focus));
  }
  EXPECT_LE(farthest_kept, nearest_dropped);
}

TEST(ChunkBvhCache, MalformedChunkIsReportedByIdAndNotCached) {
  InMemoryChunkSource source;
  Chunk bad = chunk_from_triangles(42, {flat_triangle({5, 0, 0}, {5, 1, 0}, {5, 0, 1}, {})});
  bad.indices[1] = 99;
  source.add(bad);
  auto cache = std::make_shared<ChunkBvhCache>();
  EmbreeCubeSampler sampler(cache);
  try {
    sampler.sample({0, 0, 0}, Box3d::cube({0, 0, 0}, 0.5), params(8), source);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("chunk 42"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cache->stats().cached_groups, 0u);
}

TEST(ChunkBvhCache, BvhsHeldPastTheCacheAreReleasedSafely) {
  // A BVH may outlive its cache (a cube map still holds it): Embree frees its
  // memory then and must not report that to the destroyed cache (an ASan
  // use-after-free before the cache unset its memory monitor).
  const auto owned = room({0, 0, 0}, 3);
  const InMemoryChunkSource& source = *owned;
  const std::vector<ChunkRef> refs = source.query(source.model_bounds());
  auto cache = std::make_shared<ChunkBvhCache>(one_chunk_per_group());
  auto held = cache->acquire(refs, source);
  ASSERT_EQ(held.size(), refs.size());
  EXPECT_GT(cache->stats().peak_device_bytes, 0u);
  cache.reset();
  for (const auto& bvh : held) EXPECT_NE(bvh->scene, nullptr);
  held.clear();  // scenes released after their cache
}

TEST(ChunkBvhCache, BatchedBvhsAreCachedApartFromTheOthers) {
  // A cube map traced in batches builds its groups at batch_build_quality; a
  // BVH built for one kind of cube map is never handed to the other, so the
  // order in which threads' cube maps ran cannot change what one traces.
  const auto owned = room({0, 0, 0}, 3);
  const InMemoryChunkSource& source = *owned;
  const std::vector<ChunkRef> refs = source.query(source.model_bounds());
  auto cache = std::make_shared<ChunkBvhCache>(one_chunk_per_group());
  const auto whole = cache->acquire(refs, source);
  const auto batched = cache->acquire(refs, source, true);
  ASSERT_EQ(whole.size(), refs.size());
  ASSERT_EQ(batched.size(), refs.size());
  for (std::size_t i = 0; i < refs.size(); ++i) EXPECT_NE(whole[i]->scene, batched[i]->scene);
  EXPECT_EQ(cache->stats().builds, 2 * refs.size());
  const auto again = cache->acquire(refs, source, true);
  for (std::size_t i = 0; i < refs.size(); ++i) EXPECT_EQ(again[i]->scene, batched[i]->scene);
  EXPECT_EQ(cache->stats().builds, 2 * refs.size());
  EXPECT_EQ(cache->stats().cached_groups, 2 * refs.size());
  const std::vector<ChunkGroupRefs> groups = cache->groups_of(refs, source);
  ASSERT_FALSE(groups.empty());
  EXPECT_EQ(groups[0].estimated_batch_bytes * kEstimatedBvhBytesPerTriangle,
            groups[0].estimated_bytes * kEstimatedLowQualityBvhBytesPerTriangle);
}

// An eye at standing height above the middle of the generated plant's floor.
Vec3d plant_floor_eye(const ChunkSource& source) {
  const Box3d model = source.model_bounds();
  return {model.center().x, model.center().y, model.lo.z + 1.7};
}

TEST(ChunkBvhCache, AModelThatFitsOneBatchIsOneGroupElseGroupsOfAMillionTriangles) {
  constexpr std::size_t kGiB = std::size_t{1} << 30;
  // The 12.7 M plant under the default 4 GiB cap: one group.
  EXPECT_EQ(default_group_triangles(12'700'000, 4 * kGiB), 12'700'000u);
  // Exactly half the cap at 112 B per triangle fits; one triangle more does not.
  const std::uint64_t fits = 2 * kGiB / kEstimatedBvhBytesPerTriangle;
  EXPECT_EQ(default_group_triangles(fits, 4 * kGiB), fits);
  EXPECT_EQ(default_group_triangles(fits + 1, 4 * kGiB), std::size_t{1} << 20);
  // The 82 M plant under a 2 GiB cap, the 2 M plant under 64 MiB: batches.
  EXPECT_EQ(default_group_triangles(82'000'000, 2 * kGiB), std::size_t{1} << 20);
  EXPECT_EQ(default_group_triangles(2'000'000, std::size_t{64} << 20), std::size_t{1} << 20);
  EXPECT_EQ(default_group_triangles(0, 4 * kGiB), 1u);

  const auto owned = generated_plant();
  const Vec3d eye = plant_floor_eye(*owned);
  EmbreeCubeSampler sampler(std::make_shared<ChunkBvhCache>(ChunkBvhCacheParams{}));
  sampler.sample(eye, Box3d::cube(eye, 3.0), params(32), *owned);
  EXPECT_GT(owned->query(owned->model_bounds()).size(), 1u);
  EXPECT_EQ(sampler.cache().stats().groups, 1u);
  EXPECT_EQ(sampler.stats().instances, 1u);
}

TEST(ChunkBvhCache, GroupSizeChangesNoPixel) {
  const auto owned = generated_plant();
  const InMemoryChunkSource& source = *owned;
  const Vec3d eye = plant_floor_eye(source);
  const Box3d cull = Box3d::cube(eye, 3.0);
  std::vector<CubeSample> results;
  std::vector<std::size_t> groups;
  for (std::size_t group_triangles : {std::size_t{1}, std::size_t{20000}, std::size_t{1} << 30}) {
    ChunkBvhCacheParams p;
    p.group_triangles = group_triangles;
    EmbreeCubeSampler sampler(std::make_shared<ChunkBvhCache>(p));
    results.push_back(sampler.sample(eye, cull, params(64), source));
    groups.push_back(sampler.cache().stats().groups);
  }
  EXPECT_EQ(groups[0], source.query(source.model_bounds()).size());
  EXPECT_LT(groups[1], groups[0]);
  EXPECT_GT(groups[1], 1u);
  EXPECT_EQ(groups[2], 1u);
  for (std::size_t i = 1; i < results.size(); ++i) {
    const Parity p = compare(results[0], results[i]);
    // Positions move from chunk frames to group frames (float rounding only).
    // Where neighbouring chunks store a shared edge's vertices a rounding step
    // apart, a ray exactly through the seam can hit either side or slip to
    // what lies behind: here one pixel column (64 of 24576 pixels) does.
    EXPECT_EQ(p.coverage_mismatch, 0u);
    EXPECT_GE(p.depth_agreeing_fraction(), 0.995);
    EXPECT_GE(p.psnr(), 40.0);
  }
}

// The inner source's model with every triangle under one textured material:
// texture coordinates from a planar projection of world positions (the
// texture repeats every few metres, seen magnified near the eye and minified
// far away), a 64 x 64 texture of smooth colour waves with, when `holes`,
// alpha 0 in a grid of round holes (alpha-tested).
class TexturedSource final : public ChunkSource {
 public:
  TexturedSource(const ChunkSource& inner, bool holes) : inner_(inner), holes_(holes) {}
  std::vector<ChunkRef> query(const Box3d& box) const override { return inner_.query(box); }
  std::shared_ptr<const Chunk> load(std::int64_t id) const override {
    auto chunk = std::make_shared<Chunk>(*inner_.load(id));
    chunk->uvs.clear();
    for (std::uint32_t i = 0; i < chunk->positions.size(); ++i) {
      const Vec3d w = chunk->world(i);
      chunk->uvs.push_back({float((w.x + 0.6 * w.y) * 0.31), float((w.z - 0.4 * w.y) * 0.27)});
    }
    chunk->materials.assign(chunk->triangle_count(), 1);
    return chunk;
  }
  Box3d model_bounds() const override { return inner_.model_bounds(); }
  std::vector<Material> materials() const override {
    Material m;
    m.name = "waves";
    m.texture_id = 1;
    m.alpha_test = holes_;
    return {Material{}, m};
  }
  std::shared_ptr<const TextureImage> load_texture(std::int64_t id) const override {
    auto t = std::make_shared<TextureImage>();
    t->id = id;
    t->width = t->height = 64;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        const double a = 2 * M_PI * x / 64, b = 2 * M_PI * y / 64;
        const bool hole = holes_ && std::hypot(x % 16 - 7.5, y % 16 - 7.5) < 5;
        t->texels.push_back({std::uint8_t(128 + 120 * std::sin(a)), std::uint8_t(128 + 120 * std::cos(b)),
                             std::uint8_t(128 + 100 * std::sin(a + b)), std::uint8_t(hole ? 0 : 255)});
      }
    t->has_alpha = holes_;
    return t;
  }

 private:
  const ChunkSource& inner_;
  bool holes_;
};

// Same pixels and same seen triangles, face by face.
void expect_same_cube(const CubeSample& a, const CubeSample& b, const std::string& what) {
  for (int f = 0; f < kCubeFaces; ++f) {
    const CubeFace &x = a.faces[std::size_t(f)], &y = b.faces[std::size_t(f)];
    EXPECT_EQ(x.depth, y.depth) << what << " face " << f;
    EXPECT_EQ(x.color, y.color) << what << " face " << f;
    ASSERT_EQ(x.seen.size(), y.seen.size()) << what << " face " << f;
    for (std::size_t c = 0; c < x.seen.size(); ++c) {
      EXPECT_EQ(x.seen[c].id, y.seen[c].id) << what;
      EXPECT_EQ(x.seen[c].triangles, y.seen[c].triangles) << what;
      EXPECT_EQ(x.seen[c].triangle_tiles, y.seen[c].triangle_tiles) << what;
    }
  }
}

TEST(EmbreeBatches, GroupsBeyondHalfTheCapAreTracedInBatchesWithTheSamePixels) {
  const auto owned = generated_plant();
  const InMemoryChunkSource& source = *owned;
  const Vec3d eye = plant_floor_eye(source);
  const Box3d cull = Box3d::cube(eye, 3.0);
  ChunkBvhCacheParams roomy, tight;
  roomy.group_triangles = tight.group_triangles = 20000;
  // Half the cap holds about one group's estimate.
  tight.cache_bytes = 2 * 25000 * kEstimatedBvhBytesPerTriangle;
  EmbreeCubeSampler whole(std::make_shared<ChunkBvhCache>(roomy)), batched(std::make_shared<ChunkBvhCache>(tight));
  const CubeSample a = whole.sample(eye, cull, params(64), source);
  const CubeSample b = batched.sample(eye, cull, params(64), source);
  EXPECT_EQ(whole.stats().batches, 1u);
  EXPECT_GT(batched.stats().batches, 2u);
  EXPECT_EQ(batched.stats().batches, batched.cache().stats().builds);
  expect_same_cube(a, b, "generated plant");
  // The tight cache held about one batch at a time: its peak is about half
  // the whole trace's (0.495-0.500 measured: the whole trace's peak varies
  // with how many threads join Embree's builds), where one batch holding
  // every group would peak above the whole trace (Morton BVHs are larger).
  EXPECT_LT(double(batched.cache().stats().peak_device_bytes), 0.6 * double(whole.cache().stats().peak_device_bytes));
  EXPECT_LE(batched.cache().stats().cached_groups, 2u);
}

TEST(EmbreeBatches, GroupsBehindEarlierHitsAreSkippedUnbuilt) {
  // A closed room around the eye, and a second room 40 m away that its walls hide.
  auto owned = room({0, 0, 0});
  const auto other = room({40, 0, 0}, 3);
  const std::vector<ChunkRef> far_refs = other->query(other->model_bounds());
  for (const ChunkRef& r : far_refs) {
    Chunk c = *other->load(r.id);
    c.id += 100;
    owned->add(std::move(c));
  }
  const InMemoryChunkSource& source = *owned;
  const std::size_t chunks = source.query(source.model_bounds()).size();
  EmbreeCubeSampler whole(std::make_shared<ChunkBvhCache>(one_chunk_per_group()));
  EmbreeCubeSampler batched(std::make_shared<ChunkBvhCache>(one_chunk_per_group(1)));
  const Vec3d eye{0.1, 0.2, 0.3};
  const Box3d cull = Box3d::cube({0, 0, 0}, 1.0);
  const CubeSample a = whole.sample(eye, cull, params(32), source);
  const CubeSample b = batched.sample(eye, cull, params(32), source);
  expect_same_cube(a, b, "room beside a hidden room");
  EXPECT_EQ(batched.stats().groups_hidden, far_refs.size());
  EXPECT_EQ(batched.cache().stats().builds, chunks - far_refs.size());
  EXPECT_EQ(whole.cache().stats().builds, chunks);
}

TEST(EmbreeBatches, AlphaTestedHitsAndSecondSegmentsAcrossBatches) {
  const auto owned = room({0, 0, 0}, 9);
  const TexturedSource source(*owned, true);
  // Every chunk its own group and batch (a 1-byte cap), against one batch;
  // one eye inside the cull box, one outside it (second ray segments).
  for (const Vec3d& eye : {Vec3d{0.1, 0.2, 0.3}, Vec3d{2.5, -1.5, 0.5}}) {
    EmbreeCubeSampler whole(std::make_shared<ChunkBvhCache>(one_chunk_per_group()));
    EmbreeCubeSampler batched(std::make_shared<ChunkBvhCache>(one_chunk_per_group(1)));
    const Box3d cull = Box3d::cube({0, 0, 0}, 1.0);
    const CubeSample a = whole.sample(eye, cull, params(32), source);
    const CubeSample b = batched.sample(eye, cull, params(32), source);
    EXPECT_EQ(batched.stats().batches, source.query(source.model_bounds()).size());
    EXPECT_GT(batched.stats().alpha_retraces, 0u);
    EXPECT_EQ(batched.stats().second_rays > 0, eye.x > 1.0);
    expect_same_cube(a, b, "textured room");
  }
}

TEST(SampleBackends, TexturedModelsMatchIncludingAlphaTestedHoles) {
  const auto owned = room({0, 0, 0});
  for (bool holes : {false, true}) {
    const TexturedSource source(*owned, holes);
    Backends backends;
    backends.check({0.5, -0.3, 0.2}, Box3d::cube({0, 0, 0}, 1.0), params(128),
                   source, holes ? "textured, alpha-tested holes" : "textured");
    EXPECT_EQ(backends.embree.stats().alpha_retraces > 0, holes) << "alpha-tested hits are traced again";
  }
}

TEST(SampleBackendConfig, NamesParseAndAutoResolvesToARealBackend) {
  for (SampleBackend b : {SampleBackend::osmesa, SampleBackend::egl, SampleBackend::embree, SampleBackend::automatic})
    EXPECT_EQ(parse_sample_backend(sample_backend_name(b)), b);
  EXPECT_THROW(parse_sample_backend("vulkan"), std::invalid_argument);
  EXPECT_NE(resolve_sample_backend(SampleBackend::automatic), SampleBackend::automatic);
  // Without a GPU, auto is Embree and has nothing to explain; with one that
  // EGL can draw on, EGL.
  if (!egl_hardware_device_present()) {
    EXPECT_EQ(resolve_sample_backend(SampleBackend::automatic), SampleBackend::embree);
    EXPECT_EQ(automatic_backend_note(), "");
  } else if (egl_hardware_context_error().empty()) {
    EXPECT_EQ(resolve_sample_backend(SampleBackend::automatic), SampleBackend::egl);
  }
  EXPECT_STREQ(sample_backend_pixels(SampleBackend::osmesa), "gl");
  EXPECT_STREQ(sample_backend_pixels(SampleBackend::embree), "embree");
  EXPECT_EQ(CubeSamplerFactory(SampleBackend::embree, 1 << 20).make()->backend_name(), "embree");
  EXPECT_EQ(CubeSamplerFactory(SampleBackend::embree, 1 << 20).make()->device(), "CPU");
  auto gl = CubeSamplerFactory(SampleBackend::osmesa, 1 << 20).make();
  EXPECT_EQ(gl->backend_name(), "osmesa");
  EXPECT_FALSE(gl->device().empty());  // the GL_RENDERER string, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  gl->end_work();
}

}  // namespace
}  // namespace cellbake
