// The fixed light model (stages/shading.h) as ChunkRenderer draws it,
// with analytic answers: Lambert's cosine between a plane facing the key
// light and one tilted away, two-sided lighting, unlit = the vertex colour
// exactly, the same scene rotated from z-up to y-up lit the same, and a baked
// sample face equal to the viewer's ground truth from the same eye (the bake's
// shading travels through the database's meta `config`).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "stages/cube_map.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/shading.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "tests/fixture_cameras.h"
#include "tests/fixture_chunk_source.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"
#include "viewer/baked_config_text.h"
#include "viewer/decoded_cell.h"
#include "viewer/scene_drawer.h"

namespace cellbake {
namespace {

using test::camera_down;

using test::chunk_from_triangles;
using test::flat_triangle;

constexpr double kPi = 3.14159265358979323846;
const Vec3d kZUp{0, 0, 1}, kYUp{0, 1, 0};

std::unique_ptr<ChunkRenderer> make_renderer() {
  return std::make_unique<ChunkRenderer>(create_gl_context(GlBackend::osmesa, 1, 1));
}

// A square of side 2 around `centre` spanned by unit vectors u and v (normal u x v).
std::vector<Triangle> square(const Vec3d& centre, const Vec3d& u, const Vec3d& v, Rgba8 color) {
  const Vec3d a = centre - u - v, b = centre + u - v, c = centre + u + v, d = centre - u + v;
  return {flat_triangle(a, b, c, color), flat_triangle(a, c, d, color)};
}


struct Frame {
  std::vector<Rgba8> color;
  std::vector<float> depth;
};

Frame render(ChunkRenderer& r, const RenderCamera& camera, const std::vector<Triangle>& triangles, int size = 32) {
  const std::vector<std::shared_ptr<const Chunk>> chunks = {
      std::make_shared<const Chunk>(chunk_from_triangles(1, triangles))};
  r.clear_cache();
  r.begin_frame(size, size);
  r.draw(camera, Box3d{}, chunks);
  Frame f;
  r.read_frame(f.color, f.depth);
  return f;
}

Rgba8 centre_pixel(const Frame& f, int size = 32) { return f.color[std::size_t(size / 2) * size + size / 2]; }

int max_channel_difference(Rgba8 a, Rgba8 b) {
  return std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b), std::abs(a.a - b.a)});
}

// Only the key light, along z: the factor is exactly |cos| of the tilt.
ShadingLights key_only(double ambient = 0) {
  ShadingParams p;
  p.key_direction = {0, 0, 1};
  p.key_strength = 1;
  p.fill_strength = 0;
  p.ambient = ambient;
  return shading_lights(p, kZUp);
}

TEST(Shading, LambertRatioBetweenFacingAndTiltedPlanes) {
  auto r = make_renderer();
  r->set_shading(key_only());
  const Rgba8 base{200, 160, 80, 255};
  const RenderCamera cam = camera_down({0, 0, 5});
  const Rgba8 facing = centre_pixel(render(*r, cam, square({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, base)));
  for (double tilt_deg : {30.0, 60.0, 75.0}) {
    const double t = tilt_deg * kPi / 180;
    // Tangent tilted down by `t`: normal (sin t, 0, cos t), cos t of the key light.
    const Rgba8 tilted = centre_pixel(render(*r, cam, square({0, 0, 0}, {std::cos(t), 0, -std::sin(t)}, {0, 1, 0}, base)));
    EXPECT_LE(max_channel_difference(facing, base), 1) << "facing the key light: the full colour";
    EXPECT_LE(max_channel_difference(tilted, apply_lighting(base, std::cos(t))), 1) << tilt_deg;
    EXPECT_NEAR(double(tilted.r) / facing.r, std::cos(t), 0.01) << tilt_deg;
    EXPECT_EQ(tilted.a, 255);
  }
  // The CPU reference agrees with the configured model.
  EXPECT_NEAR(lighting_factor(key_only(), {std::sin(1.0), 0, std::cos(1.0)}), std::cos(1.0), 1e-12);
}

TEST(Shading, LitColoursAreClampedAndAlphaKept) {
  auto r = make_renderer();
  r->set_shading(key_only(1.0));  // factor 2 for a plane facing the light
  const Frame f = render(*r, camera_down({0, 0, 5}), square({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, Rgba8{200, 100, 0, 128}));
  EXPECT_LE(max_channel_difference(centre_pixel(f), Rgba8{255, 200, 0, 128}), 1);
  EXPECT_EQ(apply_lighting(Rgba8{200, 100, 0, 128}, 2.0), (Rgba8{255, 200, 0, 128}));
}

TEST(Shading, TwoSidedBackFacesAreLitLikeTheirFronts) {
  auto r = make_renderer();  // the default lights
  const Rgba8 base{180, 180, 180, 255};
  const double t = 0.7;
  const std::vector<Triangle> plane = square({0, 0, 0}, {std::cos(t), 0, -std::sin(t)}, {0, 1, 0}, base);
  const Rgba8 above = centre_pixel(render(*r, camera_down({0, 0, 5}), plane));
  RenderCamera below = camera_down({0, 0, -5});
  below.forward = {0, 0, 1};
  below.up = {0, -1, 0};  // right x up = -forward
  const Rgba8 under = centre_pixel(render(*r, below, plane));
  EXPECT_LE(max_channel_difference(above, under), 1) << int(above.r) << " vs " << int(under.r);
  const double expected = lighting_factor(r->shading(), {std::sin(t), 0, std::cos(t)});
  EXPECT_LT(expected, 0.99);  // a case where lighting shows
  EXPECT_LE(max_channel_difference(above, apply_lighting(base, expected)), 1);
}

TEST(Shading, UnlitReproducesTheVertexColourExactly) {
  auto r = make_renderer();
  ShadingParams p;
  p.mode = ShadingMode::unlit;
  r->set_shading(shading_lights(p, kZUp));
  const Rgba8 base{37, 150, 222, 255};
  const double t = 0.9;
  const Frame f = render(*r, camera_down({0, 0, 5}, 0.3),
                         square({0, 0, 0}, {std::cos(t), 0, -std::sin(t)}, {0, 1, 0}, base));
  int covered = 0;
  for (std::size_t i = 0; i < f.color.size(); ++i) {
    if (!std::isfinite(f.depth[i])) continue;
    ++covered;
    ASSERT_EQ(f.color[i], base) << "pixel " << i;
  }
  EXPECT_GT(covered, 100);
}

// z-up (x, y, z) -> y-up (x, z, -y): the rotation shading_lights applies.
Vec3d to_y_up(const Vec3d& v) { return {v.x, v.z, -v.y}; }

// A few planes facing many ways (a pyramid roof on a box) in z-up.
std::vector<Triangle> z_up_scene() {
  std::vector<Triangle> t;
  const Rgba8 c{210, 190, 150, 255};
  const Vec3d apex{0, 0, 2.5};
  const Vec3d base[4] = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  for (int i = 0; i < 4; ++i) {
    const Vec3d a = base[i], b = base[(i + 1) % 4];
    t.push_back(flat_triangle(a, b, apex, c));                              // roof
    t.push_back(flat_triangle(a, b, b - Vec3d{0, 0, 1}, c));               // wall
    t.push_back(flat_triangle(a, b - Vec3d{0, 0, 1}, a - Vec3d{0, 0, 1}, c));
  }
  for (const auto& tri : square({0, 0, 0}, {3, 0, 0}, {0, 3, 0}, Rgba8{120, 140, 120, 255})) t.push_back(tri);
  return t;
}

TEST(Shading, YUpLightsTheRotatedSceneLikeZUp) {
  auto r = make_renderer();
  const ShadingParams params;  // the defaults, in the up-axis frame
  RenderCamera cam;
  cam.eye = {4, -5, 3.5};
  cam.forward = Vec3d{-4, 5, -2.5} * (1 / length(Vec3d{-4, 5, -2.5}));
  cam.right = cross(cam.forward, kZUp) * (1 / length(cross(cam.forward, kZUp)));
  cam.up = cross(cam.right, cam.forward);
  cam.tan_left = cam.tan_bottom = -0.6;
  cam.tan_right = cam.tan_top = 0.6;
  r->set_shading(shading_lights(params, kZUp));
  const Frame z = render(*r, cam, z_up_scene(), 64);

  std::vector<Triangle> rotated = z_up_scene();
  for (Triangle& t : rotated)
    for (Vec3d& p : t.p) p = to_y_up(p);
  RenderCamera ycam = cam;
  ycam.eye = to_y_up(cam.eye);
  ycam.forward = to_y_up(cam.forward);
  ycam.right = to_y_up(cam.right);
  ycam.up = to_y_up(cam.up);
  r->set_shading(shading_lights(params, kYUp));
  const Frame y = render(*r, ycam, rotated, 64);

  int covered = 0, shades = 0;
  std::vector<Rgba8> seen;
  for (std::size_t i = 0; i < z.color.size(); ++i) {
    ASSERT_EQ(std::isfinite(z.depth[i]), std::isfinite(y.depth[i])) << "pixel " << i;
    if (!std::isfinite(z.depth[i])) continue;
    ++covered;
    EXPECT_LE(max_channel_difference(z.color[i], y.color[i]), 1) << "pixel " << i;
    if (std::find(seen.begin(), seen.end(), z.color[i]) == seen.end()) seen.push_back(z.color[i]), ++shades;
  }
  EXPECT_GT(covered, 1000);
  EXPECT_GE(shades, 4) << "the planes are lit differently";

  // The same y-up scene under the z-up mapping is lit differently: the test has teeth.
  r->set_shading(shading_lights(params, kZUp));
  const Frame wrong = render(*r, ycam, rotated, 64);
  int differ = 0;
  for (std::size_t i = 0; i < z.color.size(); ++i)
    differ += std::isfinite(z.depth[i]) && max_channel_difference(z.color[i], wrong.color[i]) > 4;
  EXPECT_GT(differ, covered / 4);
}

TEST(Shading, LightsValidateAndMapUpAxes) {
  ShadingParams p;
  p.key_direction = {0, 2, 0};
  const ShadingLights y = shading_lights(p, kYUp);
  EXPECT_EQ(y.key, (Vec3d{0, 0, -1}));  // the frame's y (horizontal) is world -z for a y-up model
  p.key_direction = {0, 0, 3};
  EXPECT_EQ(shading_lights(p, kYUp).key, (Vec3d{0, 1, 0}));  // up is up
  p.key_direction = {0, 0, 0};
  EXPECT_THROW(shading_lights(p, kZUp), std::invalid_argument);
  p = ShadingParams{};
  p.ambient = -0.1;
  EXPECT_THROW(shading_lights(p, kZUp), std::invalid_argument);
  EXPECT_THROW(shading_lights(ShadingParams{}, Vec3d{1, 0, 0}), std::invalid_argument);
  auto r = make_renderer();
  ShadingLights bad = shading_lights(ShadingParams{}, kZUp);
  bad.key = {0, 0, 2};
  EXPECT_THROW(r->set_shading(bad), std::invalid_argument);
}

TEST(Shading, ConfigTextRoundTripAndOlderDatabasesAreUnlit) {
  BakeConfig c;
  c.shading.key_direction = {0.1, -0.2, 0.9};
  c.shading.key_strength = 0.55;
  c.shading.fill_direction = {1, 0, 0.25};
  c.shading.fill_strength = 0.125;
  c.shading.ambient = 0.4;
  const ShadingParams back = shading_of_config_text(describe_bake_config(c));
  EXPECT_EQ(back.mode, ShadingMode::lit);
  EXPECT_EQ(back.key_direction, c.shading.key_direction);
  EXPECT_EQ(back.key_strength, c.shading.key_strength);
  EXPECT_EQ(back.fill_direction, c.shading.fill_direction);
  EXPECT_EQ(back.fill_strength, c.shading.fill_strength);
  EXPECT_EQ(back.ambient, c.shading.ambient);
  c.shading.mode = ShadingMode::unlit;
  EXPECT_EQ(shading_of_config_text(describe_bake_config(c)).mode, ShadingMode::unlit);
  // Baked before shading existed: no shading lines, drawn as baked.
  EXPECT_EQ(shading_of_config_text("up=z\ncells.size=2\n").mode, ShadingMode::unlit);
  EXPECT_EQ(shading_of_config_text("").mode, ShadingMode::unlit);
  EXPECT_THROW(shading_of_config_text("shading.mode=glossy\n"), std::invalid_argument);
  EXPECT_THROW(shading_of_config_text("shading.mode=lit\nshading.key_direction=1,2\n"), std::invalid_argument);
  EXPECT_THROW(shading_of_config_text("shading.mode=lit\nshading.ambient=x\n"), std::invalid_argument);
}

// The room of tests/fixture_room_obj.h baked with the default (lit) shading
// into one sample per cell, PNG faces; the near budget 0 keeps the cull box
// empty, so every face shows the whole room around the sample point.
TEST(Shading, BakedSampleFaceMatchesTheViewersTruthFromTheSameEye) {
  test::TempDir dir;
  BakeConfig c = test::obj_room_bake_config(dir.path(), test::pillar_room_obj(), Box3d{{1, 5, 1.6}, {3, 7, 1.6}}, 0, 64);
  c.samples_initial = "centre";
  c.samples_max = 1;
  c.far_choice = "tdm";  // the sample's images must be stored whole (exact geometry would replace them)
  ASSERT_EQ(test::bake_quietly(c, 1).cells_baked, 1u);

  CellDb db(c.database, CellDb::Mode::read_only);
  const auto row = db.get_cell(1, true);
  ASSERT_TRUE(row);
  const DecodedCell cell = decode_cell(*row);
  ASSERT_EQ(cell.samples.size(), 1u);
  GeometryStore store(c.store);
  SceneDrawer drawer(std::shared_ptr<GlContext>(create_gl_context(GlBackend::osmesa, 1, 1)), store);
  const ShadingParams shading = shading_of_config_text(db.meta("config").value_or(""));
  ASSERT_EQ(shading.mode, ShadingMode::lit);

  std::size_t compared = 0, close = 0, unlike_unlit = 0;
  ShadingParams unlit;
  unlit.mode = ShadingMode::unlit;
  for (const DecodedFace& f : cell.faces) {
    const RenderCamera cam = cube_face_camera(f.eye, f.face, c.near_plane);
    ViewFrame truth, flat;
    drawer.set_shading(shading_lights(shading, kZUp));
    drawer.draw_truth(cam, 64, 64, SceneDrawOptions{}, truth);
    drawer.set_shading(shading_lights(unlit, kZUp));
    drawer.draw_truth(cam, 64, 64, SceneDrawOptions{}, flat);
    ASSERT_EQ(f.image.pixels.size(), truth.color.size());
    for (std::size_t i = 0; i < truth.color.size(); ++i) {
      if (!truth.covered(i)) continue;
      ++compared;
      close += max_channel_difference(f.image.pixels[i], truth.color[i]) <= 2;
      unlike_unlit += max_channel_difference(f.image.pixels[i], flat.color[i]) > 4;
    }
  }
  EXPECT_EQ(compared, 6u * 64 * 64);  // a closed room
  // Equal but where surfaces meet at an edge and draw order decides a tie.
  EXPECT_GT(double(close) / compared, 0.99) << close << " of " << compared;
  // And lit: the baked colours are not the vertex colours.
  EXPECT_GT(double(unlike_unlit) / compared, 0.5) << unlike_unlit << " of " << compared;
}

}  // namespace
}  // namespace cellbake
