// Appearance (issue 11) end to end with analytic answers: a checkerboard
// texture (every square its own colour) on a 2 m wall quad, ingested from
// OBJ + map_Kd and from a hand-built GLB with an embedded PNG, renders its
// squares at the projected square centres in the truth (ChunkRenderer), in a
// sample cube face (sample_cube) and in the impostor of a bake (ViewSession,
// as `cellbake render`); the ingest size cap; all-black vertex colours under a
// red Kd render red; a missing map_Kd is one named warning and the material
// colour; file normals (PLY nx ny nz) survive ingest within octahedral
// quantisation and light a flat quad as shading.h predicts; the alpha test
// drops the transparent half of a quad; a schema 1 store still opens (no
// textures); the renderer's texture cache stays under its cap while two
// textured chunks alternate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "stages/cube_map.h"
#include "stages/normal_packing.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/shading.h"
#include "stages/render/gl_sample_cube.h"
#include "stages/sample/sample.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "storage/sqlite_db.h"
#include "tests/fixture_cameras.h"
#include "tests/fixture_room_obj.h"
#include "tests/fixture_textured.h"
#include "tests/test_support.h"
#include "viewer/decoded_cell.h"
#include "viewer/view_camera.h"
#include "viewer/view_session.h"

namespace cellbake {
namespace {

using test::camera_down;

using test::checker_square_colour;
using test::checker_texels;
using test::checker_wall;
using test::TempDir;
using test::TexturedQuad;
using test::write_png_bottom_up;
using test::write_text;
using test::write_textured_quad_obj;

constexpr double kPi = 3.14159265358979323846;
constexpr int kSquares = 8, kSquarePx = 8, kTexSize = kSquares * kSquarePx;
const Vec3d kZUp{0, 0, 1};
const Vec3d kWallEye{2, 6, 1.6};  // 2 m in front of the checker wall's centre

const ParallelFor kSerial = [](std::size_t n, const std::function<void(std::size_t)>& fn) {
  for (std::size_t i = 0; i < n; ++i) fn(i);
};

IngestReport ingest(const std::vector<std::filesystem::path>& models, const std::filesystem::path& store,
                    IngestParams params = {}) {
  return ingest_models(models, store, params, kSerial);
}

ShadingLights unlit() {
  ShadingParams p;
  p.mode = ShadingMode::unlit;
  return shading_lights(p, kZUp);
}

// Only the key light, along z, strength 1, no ambient: the factor is |n.z|.
ShadingLights key_only() {
  ShadingParams p;
  p.key_direction = {0, 0, 1};
  p.key_strength = 1;
  p.fill_strength = 0;
  p.ambient = 0;
  return shading_lights(p, kZUp);
}

std::unique_ptr<ChunkRenderer> make_renderer(ChunkRendererParams params = {}) {
  return std::make_unique<ChunkRenderer>(create_headless_gl_context(1, 1), params);
}

// From kWallEye looking along +x at the checker wall (right = -y, up = +z).
RenderCamera wall_camera(double tan_half = 0.6) {
  RenderCamera c;
  c.eye = kWallEye;
  c.forward = {1, 0, 0};
  c.right = {0, -1, 0};
  c.up = {0, 0, 1};
  c.tan_left = c.tan_bottom = -tan_half;
  c.tan_right = c.tan_top = tan_half;
  return c;
}


struct Frame {
  int width = 0, height = 0;
  std::vector<Rgba8> color;
  std::vector<float> depth;
  std::size_t index(int col, int row) const { return static_cast<std::size_t>(row) * width + col; }
};

// Every chunk of `store` drawn with its materials (and textures). Chunk ids
// of different stores collide, so the renderer's chunk cache is cleared.
Frame render_store(ChunkRenderer& r, const GeometryStore& store, const RenderCamera& camera, int size) {
  r.clear_cache();
  r.use_materials_of(store);
  std::vector<std::int64_t> ids;
  for (const ChunkRef& ref : store.all_chunks()) ids.push_back(ref.id);
  r.begin_frame(size, size);
  r.draw(camera, Box3d{}, ids, [&store](std::int64_t id) { return store.load(id); });
  Frame f;
  f.width = f.height = size;
  r.read_frame(f.color, f.depth);
  return f;
}

struct Pixel {
  int col = -1, row = -1;
};

// The pixel (row 0 at the top) that world point `p` projects into.
Pixel pixel_of(const RenderCamera& c, int width, int height, const Vec3d& p) {
  const Vec3d d = p - c.eye;
  const double f = dot(d, c.forward);
  const double s = dot(d, c.right) / f, t = dot(d, c.up) / f;
  return {static_cast<int>(std::floor((s - c.tan_left) / (c.tan_right - c.tan_left) * width)),
          static_cast<int>(std::floor((c.tan_top - t) / (c.tan_top - c.tan_bottom) * height))};
}

int max_channel_difference(Rgba8 a, Rgba8 b) {
  return std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b), std::abs(a.a - b.a)});
}

std::string str(Rgba8 c) {
  std::ostringstream o;
  o << "(" << int(c.r) << " " << int(c.g) << " " << int(c.b) << " " << int(c.a) << ")";
  return o.str();
}

// Checks the pixel under the centre of every square (i, j) of `quad` against
// `expected(i, j)` within `tolerance` per channel; returns the squares that
// match and reports the first mismatches.
using SquareColour = std::function<Rgba8(int i, int j)>;
int matching_squares(const std::vector<Rgba8>& color, int width, int height, const RenderCamera& camera,
                     const TexturedQuad& quad, const SquareColour& expected, int tolerance, const std::string& what,
                     int squares = kSquares) {
  int matches = 0, reported = 0;
  for (int j = 0; j < squares; ++j)
    for (int i = 0; i < squares; ++i) {
      const Pixel px = pixel_of(camera, width, height, quad.at((i + 0.5) / squares, (j + 0.5) / squares));
      if (px.col < 0 || px.row < 0 || px.col >= width || px.row >= height) {
        ADD_FAILURE() << what << ": square " << i << "," << j << " projects outside the image";
        continue;
      }
      const Rgba8 got = color[static_cast<std::size_t>(px.row) * width + px.col];
      const Rgba8 want = expected(i, j);
      if (max_channel_difference(got, want) <= tolerance) {
        ++matches;
      } else if (reported++ < 5) {
        ADD_FAILURE() << what << ": square " << i << "," << j << " at pixel " << px.col << "," << px.row << " is "
                      << str(got) << ", expected " << str(want) << " +- " << tolerance;
      }
    }
  return matches;
}

const SquareColour kChecker = [](int i, int j) { return checker_square_colour(i, j); };

// DIR/checker.png (the 64 x 64 checkerboard) and DIR/checker.obj + .mtl (the wall quad mapping it).
std::filesystem::path write_checker_wall(const std::filesystem::path& dir) {
  write_png_bottom_up(dir / "checker.png", checker_texels(kSquares, kSquarePx), kTexSize, kTexSize);
  return write_textured_quad_obj(dir, "checker", checker_wall(), "checker", "checker.png");
}

// ---------------------------------------------------------------- checker: truth

TEST(Appearance, CheckerQuadFromObjMapKdRendersItsSquaresInTheTruth) {
  TempDir dir;
  const IngestReport report = ingest({write_checker_wall(dir.path())}, dir / "s.db");
  EXPECT_EQ(report.textures, 1u);
  EXPECT_EQ(report.texture_bytes, std::uint64_t(kTexSize) * kTexSize * 4);
  EXPECT_TRUE(report.texture_warnings.empty());
  GeometryStore store(dir / "s.db");
  EXPECT_EQ(store.schema_version(), 2);
  const std::vector<Material> materials = store.materials();
  ASSERT_EQ(materials.size(), 2u);
  EXPECT_EQ(materials[1].name, "checker");
  EXPECT_EQ(materials[1].texture_id, 1);
  EXPECT_FALSE(materials[1].alpha_test);  // opaque PNG
  const auto texture = store.load_texture(1);
  ASSERT_TRUE(texture);
  EXPECT_EQ(texture->width, kTexSize);
  EXPECT_EQ(texture->height, kTexSize);
  EXPECT_FALSE(texture->has_alpha);
  EXPECT_EQ(texture->wrap_u, TextureWrap::repeat);
  EXPECT_TRUE(texture->texels == checker_texels(kSquares, kSquarePx)) << "stored losslessly, bottom row first";

  constexpr int kSize = 128;
  const RenderCamera cam = wall_camera();
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, cam, kSize);
  EXPECT_EQ(matching_squares(f.color, kSize, kSize, cam, checker_wall(), kChecker, 2, "unlit truth"), 64);
  const Pixel centre = pixel_of(cam, kSize, kSize, checker_wall().at(0.5, 0.5));
  EXPECT_NEAR(f.depth[f.index(centre.col, centre.row)], 2.0, 1e-3);
  EXPECT_EQ(r->stats().texture_uploads, 1u);

  // Lit by the default lights: each square is its texel times the wall's factor.
  const ShadingLights lights = shading_lights(ShadingParams{}, kZUp);
  const double factor = lighting_factor(lights, {1, 0, 0});
  ASSERT_LT(factor, 0.9);  // the lighting shows
  r->set_shading(lights);
  const Frame lit = render_store(*r, store, cam, kSize);
  EXPECT_EQ(matching_squares(lit.color, kSize, kSize, cam, checker_wall(),
                             [&](int i, int j) { return apply_lighting(checker_square_colour(i, j), factor); }, 2,
                             "lit truth"),
            64);
}

// `ingest --max-texture-size`: the 64-texel checker halved to 16 texels (2 per
// square, box-filtered within squares) still shows every square.
TEST(Appearance, TextureSizeCapHalvesTheImageAndTheSquaresStayInPlace) {
  TempDir dir;
  IngestParams params;
  params.max_texture_size = 20;  // 64 -> 32 -> 16
  const IngestReport report = ingest({write_checker_wall(dir.path())}, dir / "s.db", params);
  EXPECT_EQ(report.texture_bytes, 16u * 16 * 4);
  GeometryStore store(dir / "s.db");
  const auto texture = store.load_texture(1);
  ASSERT_EQ(texture->width, 16);
  ASSERT_EQ(texture->height, 16);
  EXPECT_TRUE(texture->texels == checker_texels(kSquares, 2));
  constexpr int kSize = 128;
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, wall_camera(), kSize);
  EXPECT_EQ(matching_squares(f.color, kSize, kSize, wall_camera(), checker_wall(), kChecker, 2, "capped"), 64);
}

// ---------------------------------------------------------------- checker: sample face

TEST(Appearance, CheckerQuadShowsInTheSampleCubeFace) {
  TempDir dir;
  ingest({write_checker_wall(dir.path())}, dir / "s.db");
  GeometryStore store(dir / "s.db");
  auto r = make_renderer();
  r->set_shading(unlit());
  SampleParams params;
  params.face_size = 128;
  const CubeSample sample = sample_cube(kWallEye, Box3d{}, params, store, *r);
  const CubeFace& face = sample.faces[0];  // +X
  const RenderCamera cam = cube_face_camera(kWallEye, 0);  // tangents -1..1: the face's pixel grid
  EXPECT_EQ(matching_squares(face.color, face.size, face.size, cam, checker_wall(), kChecker, 2, "sample face +X"),
            64);
  const Pixel centre = pixel_of(cam, face.size, face.size, checker_wall().at(0.5, 0.5));
  EXPECT_NEAR(face.depth[std::size_t(centre.row) * face.size + centre.col], 2.0, 1e-3);
  // The other faces see nothing (a single quad in front of the eye).
  for (int f = 1; f < kCubeFaces; ++f)
    EXPECT_TRUE(std::all_of(sample.faces[f].depth.begin(), sample.faces[f].depth.end(),
                            [](float d) { return std::isinf(d); }))
        << "face " << f;
}

// ---------------------------------------------------------------- checker: impostor

// Baked (unlit, one sample at the cell centre, near budget 0 so the whole wall
// is far field, 128-pixel PNG faces) and rendered through ViewSession as
// `cellbake render` does: the impostor, drawn from the sample's textured depth
// meshes only, shows the checker where the truth does. (The face's 64 pixels
// per unit tangent put one face pixel on each texel of the wall, so at the
// sample point the impostor matches the truth exactly here: measured PSNR +inf.)
TEST(Appearance, CheckerQuadShowsInTheImpostorAfterABake) {
  TempDir dir;
  write_png_bottom_up(dir / "checker.png", checker_texels(kSquares, kSquarePx), kTexSize, kTexSize);
  write_text(dir / "checker.mtl", "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n");
  BakeConfig c = test::obj_room_bake_config(dir.path(), test::textured_quad_obj(checker_wall(), "checker.mtl", "checker"),
                                            Box3d{{1, 5, 1.6}, {3, 7, 1.6}}, 0, 128);
  c.samples_initial = "centre";
  c.samples_max = 1;
  c.shading.mode = ShadingMode::unlit;
  c.far_choice = "tdm";  // the texture must reach the depth mesh's image (2 triangles would be drawn as geometry)
  ASSERT_EQ(test::bake_quietly(c, 1).cells_baked, 1u);

  Vec3d eye;
  {
    CellDb db(c.database, CellDb::Mode::read_only);
    const auto row = db.get_cell(1, true);
    ASSERT_TRUE(row);
    const DecodedCell cell = decode_cell(*row);
    ASSERT_EQ(cell.samples.size(), 1u);
    EXPECT_TRUE(cell.near_ids.empty()) << "the wall must be far field only";
    eye = cell.samples[0].eye;
  }
  ASSERT_LT(eye.x, 3.5);  // in front of the wall

  constexpr int kSize = 128;
  ViewRequest request;
  request.eye = eye;
  request.look = eye + Vec3d{1, 0, 0};
  request.width = request.height = kSize;
  request.max_samples = 1;
  ViewSession session(c.database);
  const ViewResult result = session.render(request, ViewMode::diff, stderr);
  EXPECT_EQ(result.cell_id, 1);
  ASSERT_FALSE(result.fallback) << result.fallback_reason;
  ASSERT_TRUE(result.impostor && result.truth);
  const RenderCamera cam = look_at_camera(request.eye, request.look, kZUp, request.fov_y_deg, kSize, kSize,
                                          request.near_plane);
  EXPECT_EQ(matching_squares(result.truth->color, kSize, kSize, cam, checker_wall(), kChecker, 2, "viewer truth"), 64);
  EXPECT_EQ(matching_squares(result.impostor->color, kSize, kSize, cam, checker_wall(), kChecker, 4, "impostor"), 64);
  ASSERT_TRUE(result.metrics);
  EXPECT_GT(result.metrics->psnr_db, 30) << "impostor vs truth of a textured wall (+inf when identical)";
  // Drawn from the sample's textured depth meshes alone.
  EXPECT_GT(result.impostor_stats.far_triangles, 0u);
  EXPECT_EQ(result.impostor_stats.chunk_triangles, 0u);
}

// ---------------------------------------------------------------- materials

// An exporter's "v x y z 0 0 0" on every vertex under a red Kd: the reader
// and store parts are in test_readers / test_ingest; here it renders red, lit
// and unlit.
TEST(Appearance, AllBlackVertexColoursUnderARedMaterialRenderRed) {
  TempDir dir;
  write_text(dir / "k.mtl", "newmtl red\nKd 0.8 0 0\n");
  write_text(dir / "kitchen.obj",
             "mtllib k.mtl\nusemtl red\n"
             "v 0 0 0 0 0 0\nv 1 0 0 0 0 0\nv 0 1 0 0 0 0\nv 1 1 0 0 0 0\n"
             "f 1 2 4\nf 1 4 3\n");
  ingest({dir / "kitchen.obj"}, dir / "s.db");
  GeometryStore store(dir / "s.db");
  constexpr int kSize = 16;
  const RenderCamera cam = camera_down({0.5, 0.5, 5}, 0.08);  // the floor fills the view
  auto r = make_renderer();
  const Rgba8 red{204, 0, 0, 255};
  for (const bool lit : {false, true}) {
    r->set_shading(lit ? shading_lights(ShadingParams{}, kZUp) : unlit());
    const Frame f = render_store(*r, store, cam, kSize);
    const Rgba8 expected = lit ? apply_lighting(red, lighting_factor(r->shading(), {0, 0, 1})) : red;
    ASSERT_GT(expected.r, 150);
    int matches = 0;
    for (std::size_t i = 0; i < f.color.size(); ++i) matches += max_channel_difference(f.color[i], expected) <= 1;
    EXPECT_EQ(matches, kSize * kSize) << (lit ? "lit" : "unlit") << ": centre " << str(f.color[f.index(8, 8)])
                                      << " expected " << str(expected);
  }
}

TEST(Appearance, MissingMapKdIngestsWithOneWarningNamingMaterialAndPath) {
  TempDir dir;
  const auto obj = write_textured_quad_obj(dir.path(), "wood", checker_wall(), "oak_planks", "textures/missing.png",
                                           "0.2 0.4 0.6");
  const IngestReport report = ingest({obj}, dir / "s.db");
  EXPECT_EQ(report.triangles_stored, 2u);
  EXPECT_EQ(report.textures, 0u);
  ASSERT_EQ(report.texture_warnings.size(), 1u);
  const std::string& warning = report.texture_warnings[0];
  EXPECT_NE(warning.find("oak_planks"), std::string::npos) << warning;
  EXPECT_NE(warning.find((dir / "textures/missing.png").lexically_normal().string()), std::string::npos) << warning;
  EXPECT_NE(warning.find("material colour used"), std::string::npos) << warning;

  GeometryStore store(dir / "s.db");
  const std::vector<Material> materials = store.materials();
  ASSERT_EQ(materials.size(), 2u);
  EXPECT_EQ(materials[1].name, "oak_planks");
  EXPECT_EQ(materials[1].texture_id, 0);
  EXPECT_FALSE(materials[1].alpha_test);
  // Drawn in the material colour.
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, wall_camera(), 64);
  EXPECT_EQ(matching_squares(f.color, 64, 64, wall_camera(), checker_wall(),
                             [](int, int) { return Rgba8{51, 102, 153, 255}; }, 1, "material colour"),
            64);

  // The CLI says it too and still succeeds.
  const auto cli = test::run_cellbake("ingest '" + obj.string() + "' --store '" + (dir / "cli.db").string() + "'");
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_NE(cli.output.find("oak_planks"), std::string::npos) << cli.output;
  EXPECT_NE(cli.output.find("missing.png"), std::string::npos) << cli.output;
}

// ---------------------------------------------------------------- GLB

// A GLB written here (one quad, TEXCOORD_0, an embedded PNG, clamp sampler):
// one stored texture with the file's wrap modes, and the checker in the truth.
TEST(Appearance, HandBuiltGlbWithEmbeddedPngRendersItsTexture) {
  TempDir dir;
  const std::vector<std::uint8_t> png = test::png_of_bottom_up(checker_texels(kSquares, kSquarePx), kTexSize, kTexSize);
  test::write_bytes(dir / "quad.glb", test::textured_quad_glb(checker_wall(), png));
  const IngestReport report = ingest({dir / "quad.glb"}, dir / "s.db");
  EXPECT_TRUE(report.texture_warnings.empty()) << report.texture_warnings.front();
  EXPECT_EQ(report.textures, 1u);
  EXPECT_EQ(report.triangles_stored, 2u);
  GeometryStore store(dir / "s.db");
  const Box3d bounds = store.summary().bounds;
  EXPECT_NEAR(bounds.lo.x, 4, 1e-6);
  EXPECT_NEAR(bounds.hi.x, 4, 1e-6);
  EXPECT_NEAR(bounds.lo.y, 5, 1e-6);
  EXPECT_NEAR(bounds.hi.z, 2.6, 1e-6);
  const std::vector<Material> materials = store.materials();
  int textured = 0;
  for (const Material& m : materials)
    if (m.texture_id == 1) {
      ++textured;
      EXPECT_EQ(m.name, "glb_checker");
      EXPECT_FALSE(m.alpha_test);
    }
  EXPECT_EQ(textured, 1);
  const auto texture = store.load_texture(1);
  ASSERT_EQ(texture->width, kTexSize);
  EXPECT_EQ(texture->wrap_u, TextureWrap::clamp);
  EXPECT_EQ(texture->wrap_v, TextureWrap::clamp);
  EXPECT_TRUE(texture->texels == checker_texels(kSquares, kSquarePx));

  constexpr int kSize = 128;
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, wall_camera(), kSize);
  EXPECT_EQ(matching_squares(f.color, kSize, kSize, wall_camera(), checker_wall(), kChecker, 2, "GLB truth"), 64);
}

// The same with a real exporter's GLB (Debian package assimp-testmodels,
// listed in scripts/install-deps.sh): the Khronos BoxTextured sample.
TEST(Appearance, BoxTexturedGlbFromAssimpTestModelsRendersItsTexture) {
  const std::filesystem::path glb = "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb";
  if (!std::filesystem::exists(glb)) GTEST_SKIP() << glb << " is missing (package assimp-testmodels)";
  TempDir dir;
  const IngestReport report = ingest({glb}, dir / "s.db");
  EXPECT_TRUE(report.texture_warnings.empty()) << report.texture_warnings.front();
  EXPECT_EQ(report.textures, 1u);
  GeometryStore store(dir / "s.db");
  int textured = 0;
  for (const Material& m : store.materials()) textured += m.texture_id == 1;
  EXPECT_EQ(textured, 1);

  const Box3d b = store.summary().bounds;
  const Vec3d centre = b.center(), extent = b.hi - b.lo;
  ASSERT_GT(length(extent), 0);
  constexpr int kSize = 96;
  const RenderCamera cam = look_at_camera(centre + Vec3d{1.3, 1.7, 1.1} * length(extent), centre, kZUp, 40, kSize,
                                          kSize, 0.01);
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, cam, kSize);
  std::size_t covered = 0, coloured = 0, greenish = 0, bluish = 0;
  std::set<std::uint32_t> distinct;
  for (std::size_t i = 0; i < f.color.size(); ++i) {
    if (!std::isfinite(f.depth[i])) continue;
    ++covered;
    const Rgba8 c = f.color[i];
    distinct.insert(std::uint32_t(c.r) << 16 | std::uint32_t(c.g) << 8 | c.b);
    coloured += std::max({c.r, c.g, c.b}) - std::min({c.r, c.g, c.b}) > 40;
    greenish += c.g > c.r + 40 && c.g > c.b + 20;
    bluish += c.b > c.r + 40 && c.b > c.g + 20;
  }
  EXPECT_GT(covered, std::size_t(kSize * kSize / 10));
  EXPECT_GT(distinct.size(), 20u) << "a texture, not a flat colour";
  EXPECT_GT(coloured, covered / 5) << "non-grey texels";
  EXPECT_GT(greenish, 0u);
  EXPECT_GT(bluish, 0u);
}

// ---------------------------------------------------------------- normals

// A patch of a sphere (radius 3) as ASCII PLY with the exact sphere normals:
// every stored vertex normal is the file's within 16-bit octahedral quantisation.
TEST(Appearance, PlyNormalsAreKeptWithinOctahedralQuantisation) {
  TempDir dir;
  struct Vertex {
    Vec3d p;
    Vec3f n;
  };
  std::vector<Vertex> vertices;
  constexpr int kU = 9, kV = 7;
  for (int j = 0; j < kV; ++j)
    for (int i = 0; i < kU; ++i) {
      const double theta = -0.5 + 1.0 * i / (kU - 1), phi = -0.4 + 0.8 * j / (kV - 1);
      const Vec3f n{static_cast<float>(std::cos(phi) * std::cos(theta)),
                    static_cast<float>(std::cos(phi) * std::sin(theta)), static_cast<float>(std::sin(phi))};
      vertices.push_back({Vec3d{n.x, n.y, n.z} * 3.0, n});
    }
  std::ostringstream ply;
  ply.precision(9);
  ply << "ply\nformat ascii 1.0\nelement vertex " << vertices.size()
      << "\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\n"
         "element face "
      << 2 * (kU - 1) * (kV - 1) << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (Vertex& v : vertices) {
    // What the file holds, as floats (printed with 9 digits: read back exactly).
    v.p = {static_cast<float>(v.p.x), static_cast<float>(v.p.y), static_cast<float>(v.p.z)};
    ply << v.p.x << " " << v.p.y << " " << v.p.z << " " << v.n.x << " " << v.n.y << " " << v.n.z << "\n";
  }
  for (int j = 0; j + 1 < kV; ++j)
    for (int i = 0; i + 1 < kU; ++i) {
      const int a = j * kU + i, b = a + 1, c = a + kU, d = c + 1;
      ply << "3 " << a << " " << b << " " << d << "\n3 " << a << " " << d << " " << c << "\n";
    }
  write_text(dir / "patch.ply", ply.str());
  ingest({dir / "patch.ply"}, dir / "s.db");
  GeometryStore store(dir / "s.db");
  std::size_t compared = 0;
  std::set<std::size_t> seen;
  for (const ChunkRef& ref : store.all_chunks()) {
    const auto chunk = store.load(ref.id);
    ASSERT_EQ(chunk->normals.size(), chunk->positions.size()) << "chunk " << ref.id;
    for (std::uint32_t v = 0; v < chunk->positions.size(); ++v) {
      const Vec3d w = chunk->world(v);
      std::size_t nearest = 0;
      for (std::size_t k = 1; k < vertices.size(); ++k)
        if (length(vertices[k].p - w) < length(vertices[nearest].p - w)) nearest = k;
      ASSERT_LT(length(vertices[nearest].p - w), 1e-5);
      const Vec3f& got = chunk->normals[v];
      const Vec3f& want = vertices[nearest].n;
      EXPECT_NEAR(got.x, want.x, 1e-3) << nearest;
      EXPECT_NEAR(got.y, want.y, 1e-3) << nearest;
      EXPECT_NEAR(got.z, want.z, 1e-3) << nearest;
      EXPECT_EQ(got, quantise_normal(want)) << "stored as packed, nothing else";
      seen.insert(nearest);
      ++compared;
    }
  }
  EXPECT_GE(compared, vertices.size());
  EXPECT_EQ(seen.size(), vertices.size());
}

// A flat quad in z = 0 whose vertex normals all tilt 50 degrees towards -x:
// lit by a key light along z alone, the quad shows cos(50) of its colour,
// while the same quad without normals (flat, facing the light) shows all of
// it; under the default lights, what lighting_factor gives for each normal.
TEST(Appearance, TiltedVertexNormalsLightAFlatQuadAsTheLightModelPredicts) {
  TempDir dir;
  const double tilt = 50 * kPi / 180;
  // Towards -x: away from the default key light, towards the fill.
  const Vec3f n{static_cast<float>(-std::sin(tilt)), 0, static_cast<float>(std::cos(tilt))};
  const auto write_quad = [&](const std::string& name, bool normals) {
    std::ostringstream ply;
    ply.precision(9);
    ply << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
    if (normals) ply << "property float nx\nproperty float ny\nproperty float nz\n";
    ply << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
           "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
    for (int k = 0; k < 4; ++k) {
      ply << (k % 2 ? 1 : -1) << " " << (k / 2 ? 1 : -1) << " 0 ";
      if (normals) ply << n.x << " " << n.y << " " << n.z << " ";
      ply << "200 160 80\n";
    }
    ply << "3 0 1 3\n3 0 3 2\n";
    write_text(dir / (name + ".ply"), ply.str());
    ingest({dir / (name + ".ply")}, dir / (name + ".db"));
  };
  write_quad("tilted", true);
  write_quad("flat", false);
  GeometryStore tilted(dir / "tilted.db"), flat(dir / "flat.db");
  ASSERT_FALSE(tilted.load(tilted.all_chunks().at(0).id)->normals.empty());
  ASSERT_TRUE(flat.load(flat.all_chunks().at(0).id)->normals.empty());

  const Rgba8 base{200, 160, 80, 255};
  const Vec3f stored = quantise_normal(n);
  const Vec3d stored_d{stored.x, stored.y, stored.z};
  constexpr int kSize = 16;
  const RenderCamera cam = camera_down({0, 0, 5}, 0.1);
  auto r = make_renderer();
  for (const ShadingLights& lights : {key_only(), shading_lights(ShadingParams{}, kZUp)}) {
    r->set_shading(lights);
    const Rgba8 want_tilted = apply_lighting(base, lighting_factor(lights, stored_d));
    const Rgba8 want_flat = apply_lighting(base, lighting_factor(lights, {0, 0, 1}));
    ASSERT_GT(max_channel_difference(want_tilted, want_flat), 10) << "the normals matter";
    const Frame ft = render_store(*r, tilted, cam, kSize), ff = render_store(*r, flat, cam, kSize);
    int tilted_ok = 0, flat_ok = 0;
    for (std::size_t i = 0; i < ft.color.size(); ++i) {
      tilted_ok += max_channel_difference(ft.color[i], want_tilted) <= 1;
      flat_ok += max_channel_difference(ff.color[i], want_flat) <= 1;
    }
    EXPECT_EQ(tilted_ok, kSize * kSize) << "centre " << str(ft.color[ft.index(8, 8)]) << " expected "
                                        << str(want_tilted);
    EXPECT_EQ(flat_ok, kSize * kSize) << "centre " << str(ff.color[ff.index(8, 8)]) << " expected " << str(want_flat);
  }
  // With the key light alone the ratio is Lambert's cosine.
  EXPECT_NEAR(lighting_factor(key_only(), stored_d), std::cos(tilt), 1e-3);
}

// ---------------------------------------------------------------- alpha test

// An RGBA texture whose left half has alpha 0: only the right half of the
// quad is drawn; the left half stays background (colour 0, depth +inf).
TEST(Appearance, AlphaTestDropsTheTransparentHalfOfAQuad) {
  TempDir dir;
  std::vector<Rgba8> texels(std::size_t(kTexSize) * kTexSize);
  for (int y = 0; y < kTexSize; ++y)
    for (int x = 0; x < kTexSize; ++x)
      texels[std::size_t(y) * kTexSize + x] = x < kTexSize / 2 ? Rgba8{255, 0, 255, 0} : Rgba8{0, 200, 0, 255};
  write_png_bottom_up(dir / "leaf.png", texels, kTexSize, kTexSize);
  const IngestReport report =
      ingest({write_textured_quad_obj(dir.path(), "leaf", checker_wall(), "leaf", "leaf.png")}, dir / "s.db");
  EXPECT_TRUE(report.texture_warnings.empty());
  GeometryStore store(dir / "s.db");
  ASSERT_EQ(store.materials().size(), 2u);
  EXPECT_TRUE(store.materials()[1].alpha_test);
  EXPECT_TRUE(store.load_texture(1)->has_alpha);

  constexpr int kSize = 128;
  const RenderCamera cam = wall_camera();
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, cam, kSize);
  int left = 0, left_background = 0, right = 0, right_green = 0;
  for (int row = 0; row < kSize; ++row)
    for (int col = 0; col < kSize; ++col) {
      // Where the pixel centre's ray meets the wall plane x = 4, in texture coordinates.
      const double s = cam.tan_left + (col + 0.5) / kSize * (cam.tan_right - cam.tan_left);
      const double t = cam.tan_top - (row + 0.5) / kSize * (cam.tan_top - cam.tan_bottom);
      const Vec3d hit = cam.eye + (cam.forward + cam.right * s + cam.up * t) * 2.0;
      const double u = (7 - hit.y) / 2, v = (hit.z - 0.6) / 2;
      if (v < 0.03 || v > 0.97) continue;
      const std::size_t i = f.index(col, row);
      if (u > 0.03 && u < 0.47) {
        ++left;
        left_background += std::isinf(f.depth[i]) && f.color[i] == Rgba8{0, 0, 0, 0};
      } else if (u > 0.53 && u < 0.97) {
        ++right;
        right_green += std::abs(f.depth[i] - 2.0f) < 1e-3f && max_channel_difference(f.color[i], {0, 200, 0, 255}) <= 2;
      }
    }
  EXPECT_GT(left, 1000);
  EXPECT_GT(right, 1000);
  EXPECT_EQ(left_background, left);
  EXPECT_EQ(right_green, right);
}

// ---------------------------------------------------------------- schema 1

// A schema 1 store (materials without texture_id / alpha_test, no textures
// table), made from a schema 2 one: it opens, its chunks load and draw, and
// no material is textured.
TEST(Appearance, SchemaOneStoreOpensWithoutTextures) {
  TempDir dir;
  ingest({write_checker_wall(dir.path())}, dir / "s.db");
  {
    SqliteDb db(dir / "s.db", SqliteDb::Mode::read_write_create);
    db.exec(
        "BEGIN;"
        "CREATE TABLE materials_v1(id INTEGER PRIMARY KEY, name TEXT NOT NULL, r INTEGER, g INTEGER, b INTEGER,"
        " a INTEGER, texture TEXT NOT NULL);"
        "INSERT INTO materials_v1 SELECT id, name, r, g, b, a, texture FROM materials;"
        "DROP TABLE materials;"
        "ALTER TABLE materials_v1 RENAME TO materials;"
        "DROP TABLE textures;"
        "UPDATE meta SET value = '1' WHERE key = 'schema_version';"
        "COMMIT;");
  }
  GeometryStore store(dir / "s.db");
  EXPECT_EQ(store.schema_version(), 1);
  const std::vector<Material> materials = store.materials();
  ASSERT_EQ(materials.size(), 2u);
  EXPECT_EQ(materials[1].name, "checker");
  EXPECT_FALSE(materials[1].texture.empty()) << "the reference is kept";
  for (const Material& m : materials) {
    EXPECT_EQ(m.texture_id, 0);
    EXPECT_FALSE(m.alpha_test);
  }
  EXPECT_THROW(store.load_texture(1), std::runtime_error);
  std::size_t triangles = 0;
  for (const ChunkRef& ref : store.all_chunks()) triangles += store.load(ref.id)->triangle_count();
  EXPECT_EQ(triangles, 2u);
  // Drawn untextured: the white material colour everywhere.
  auto r = make_renderer();
  r->set_shading(unlit());
  const Frame f = render_store(*r, store, wall_camera(), 64);
  EXPECT_EQ(matching_squares(f.color, 64, 64, wall_camera(), checker_wall(),
                             [](int, int) { return Rgba8{255, 255, 255, 255}; }, 0, "schema 1"),
            64);
  EXPECT_EQ(r->stats().texture_uploads, 0u);
}

// ---------------------------------------------------------------- texture cache cap

Chunk textured_chunk(std::int64_t id, const TexturedQuad& q, std::uint32_t material) {
  Chunk chunk;
  chunk.id = id;
  const Vec3d corners[4] = {q.c00, q.c10, q.c11, q.c01};
  const Uv uvs[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const Vec3d& c : corners) chunk.bounds.expand(c);
  chunk.origin = chunk.bounds.center();
  for (int k = 0; k < 4; ++k) {
    const Vec3d r = corners[k] - chunk.origin;
    chunk.positions.push_back({static_cast<float>(r.x), static_cast<float>(r.y), static_cast<float>(r.z)});
    chunk.colors.push_back({255, 255, 255, 255});
    chunk.uvs.push_back(uvs[k]);
  }
  chunk.indices = {0, 1, 2, 0, 2, 3};
  chunk.materials = {material, material};
  return chunk;
}

// A second texture, unlike the checker square by square.
Rgba8 other_square_colour(int i, int j) {
  return {static_cast<std::uint8_t>((i + j) % 2 ? 240 : 10), static_cast<std::uint8_t>(20 + 30 * j),
          static_cast<std::uint8_t>(20 + 30 * i), 255};
}

// Two 1 m quads side by side, each with its own 64 x 64 texture, and a cache
// cap that holds one texture: alternating frames (A, B, A and B, B and A)
// re-upload as needed, never hold more than the cap, and draw both right.
TEST(Appearance, TextureCacheStaysUnderItsCapWhileTwoTexturedChunksAlternate) {
  const TexturedQuad a{{4, 7, 1.1}, {4, 6, 1.1}, {4, 6, 2.1}, {4, 7, 2.1}};  // left half of the view
  const TexturedQuad b{{4, 6, 1.1}, {4, 5, 1.1}, {4, 5, 2.1}, {4, 6, 2.1}};  // right half
  std::vector<Rgba8> other(std::size_t(kTexSize) * kTexSize);
  for (int y = 0; y < kTexSize; ++y)
    for (int x = 0; x < kTexSize; ++x) other[std::size_t(y) * kTexSize + x] = other_square_colour(x / kSquarePx, y / kSquarePx);
  const std::vector<Rgba8> checker_image = checker_texels(kSquares, kSquarePx);
  std::vector<std::shared_ptr<const TextureImage>> images;
  for (const std::vector<Rgba8>* texels : {&checker_image, static_cast<const std::vector<Rgba8>*>(&other)}) {
    auto image = std::make_shared<TextureImage>();
    image->id = std::int64_t(images.size()) + 1;
    image->width = image->height = kTexSize;
    image->texels = *texels;
    images.push_back(image);
  }
  const std::size_t one_texture = images[0]->bytes() * 4 / 3;  // with its mip chain
  ChunkRendererParams params;
  params.texture_cache_bytes = one_texture + one_texture / 2;
  auto r = make_renderer(params);
  r->set_shading(unlit());
  int loads = 0;
  Material ma, mb;
  ma.name = "a";
  ma.texture_id = 1;
  mb.name = "b";
  mb.texture_id = 2;
  r->set_materials({Material{}, ma, mb}, [&](std::int64_t id) {
    ++loads;
    return images.at(std::size_t(id - 1));
  });
  const std::vector<std::shared_ptr<const Chunk>> chunk_a = {std::make_shared<const Chunk>(textured_chunk(1, a, 1))},
                                                  chunk_b = {std::make_shared<const Chunk>(textured_chunk(2, b, 2))};
  const SquareColour checker = kChecker, second = [](int i, int j) { return other_square_colour(i, j); };
  constexpr int kSize = 128;
  const RenderCamera cam = wall_camera();
  const std::vector<std::vector<int>> frames = {{0}, {1}, {0}, {1}, {0, 1}, {1, 0}};
  for (std::size_t k = 0; k < frames.size(); ++k) {
    r->begin_frame(kSize, kSize);
    for (int which : frames[k]) r->draw(cam, Box3d{}, which == 0 ? chunk_a : chunk_b);
    Frame f;
    f.width = f.height = kSize;
    r->read_frame(f.color, f.depth);
    const ChunkRendererStats s = r->stats();
    EXPECT_LE(s.cached_texture_bytes, params.texture_cache_bytes) << "frame " << k;
    EXPECT_EQ(s.cached_textures, 1u) << "frame " << k;
    for (int which : frames[k]) {
      const std::string what = "frame " + std::to_string(k) + (which == 0 ? " quad A" : " quad B");
      EXPECT_EQ(matching_squares(f.color, kSize, kSize, cam, which == 0 ? a : b, which == 0 ? checker : second, 2, what),
                64);
    }
    if (frames[k].size() == 1) {  // the other quad's place stays background
      const TexturedQuad& absent = frames[k][0] == 0 ? b : a;
      const Pixel px = pixel_of(cam, kSize, kSize, absent.at(0.5, 0.5));
      EXPECT_TRUE(std::isinf(f.depth[f.index(px.col, px.row)])) << "frame " << k;
    }
  }
  // Uploads: A, B, A, B, then A and B in one frame (B stays cached), then only A.
  EXPECT_EQ(r->stats().texture_uploads, 7u);
  EXPECT_EQ(loads, 7);
}

}  // namespace
}  // namespace cellbake
