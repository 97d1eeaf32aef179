// Registration of the far field at its sample point: an impostor (cube sample
// -> dense depth meshes -> simplified -> encoded and decoded -> drawn with
// TdmRenderer, as viewer/scene_drawer.cpp draws the far field) seen from the
// sample point must put the edges of thin bars where the ground truth
// (ChunkRenderer::draw of every chunk) puts them, to a tenth of a pixel, and
// must not crack.
//
// Scenes: a closed room (grey, turned 17 degrees about z so no wall is
// parallel to a cube face) around the eye, either with thin bars in front of
// it (vertical ones tilted a few degrees, horizontal ones, 5-20 m away) or
// with stripes painted on its walls and floor (coplanar quads: the simplifier
// turns each plane into a few large triangles, so the stripes live only in the
// texture). Bars and stripes come in six colours that each move the grey along
// one colour axis (+-R, +-G, +-B). Along each scanline across a bar, the bar's
// weight of a pixel is its colour's step from the grey along that axis (1
// inside the bar, 0 on the wall, linear in blends), and the bar's position is
// the weighted centroid and its width the sum of weights over a window around
// it: both are unchanged by a symmetric blur (bilinear texture filtering), so
// they compare the impostor's geometry and texture placement with the truth's
// (antialiased, 8x8 supersampled) at sub-pixel precision. Views look in
// several directions (across cube-face edges too) at a resolution and field
// of view unlike the faces'. Set CELLBAKE_KEEP_TEST_DIRS to keep the frames as
// PNGs, CELLBAKE_REGISTRATION_VERBOSE to print every bar.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "stages/depth_mesh.h"
#include "stages/encode/encode.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_sample_cube.h"
#include "stages/sample/sample.h"
#include "stages/simplify/simplify.h"
#include "tests/fixture_chunk_source.h"
#include "tests/test_support.h"
#include "viewer/shared_gl_context.h"
#include "viewer/tdm_renderer.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

using test::chunk_from_triangles;
using test::flat_triangle;
using test::InMemoryChunkSource;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180;
const Vec3d kEye{0.37, -0.21, 1.6};
const Rgba8 kWall{128, 128, 128, 255};

// Bar colours: the wall's grey moved by 127 along +R, -R, +G, -G, +B, -B.
struct BarColor {
  Rgba8 rgba;
  int channel;  // 0, 1, 2
  int sign;     // +1 or -1
};
const std::array<BarColor, 6> kBarColors = {
    BarColor{{255, 128, 128, 255}, 0, +1}, BarColor{{128, 128, 1, 255}, 2, -1},
    BarColor{{128, 255, 128, 255}, 1, +1}, BarColor{{1, 128, 128, 255}, 0, -1},
    BarColor{{128, 128, 255, 255}, 2, +1}, BarColor{{128, 1, 128, 255}, 1, -1}};

// The weight of bar colour `b` in pixel colour `c`: 0 for the wall, 1 for the bar.
double bar_weight(const BarColor& b, const Rgba8& c) {
  const int v = b.channel == 0 ? c.r : (b.channel == 1 ? c.g : c.b);
  return b.sign * (v - 128) / 127.0;
}

// The 12 triangles of a box with centre `c`, orthonormal axes a[k] and half sizes h[k].
void add_box(std::vector<Triangle>& out, const Vec3d& c, const std::array<Vec3d, 3>& a, const std::array<double, 3>& h,
             Rgba8 color) {
  std::array<Vec3d, 8> p;
  for (int k = 0; k < 8; ++k)
    p[k] = c + a[0] * (k & 1 ? h[0] : -h[0]) + a[1] * (k & 2 ? h[1] : -h[1]) + a[2] * (k & 4 ? h[2] : -h[2]);
  static constexpr int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& q : quads) {
    out.push_back(flat_triangle(p[q[0]], p[q[1]], p[q[2]], color));
    out.push_back(flat_triangle(p[q[0]], p[q[2]], p[q[3]], color));
  }
}

struct Scene {
  InMemoryChunkSource source;  // chunk 1: the room; 2...: one bar each
};

// A plane o + h h_axis + v v_axis (|h| <= half_h, |v| <= half_v) painted with
// stripes along v_axis, tilted by tilt_deg towards h_axis, `spacing` apart, in
// the bar colours from `first_color` on, grey between (plain grey when spacing is 0): coplanar quads, so the
// depth mesh sees one plane and the simplifier turns it into a few large
// triangles; the stripes then live only in the texture.
void add_painted_plane(std::vector<Triangle>& out, const Vec3d& o, const Vec3d& h_axis, const Vec3d& v_axis,
                       double half_h, double half_v, double spacing, double tilt_deg, int first_color) {
  const double slope = std::tan(tilt_deg * kDegree), shift = half_v * std::abs(slope);
  const double widths[3] = {0.12, 0.2, 0.28};
  // Boundary lines between bands, as their h at v = -half_v and at v = +half_v.
  std::vector<std::pair<double, double>> lines = {{-half_h, -half_h}};
  int k = 0;
  for (double h = -half_h + shift + 1; spacing > 0 && h + 0.3 + shift + 1 < half_h; h += spacing, ++k)
    for (double edge : {h, h + widths[k % 3]}) lines.push_back({edge - half_v * slope, edge + half_v * slope});
  lines.push_back({half_h, half_h});
  const auto at = [&](double h, double v) { return o + h_axis * h + v_axis * v; };
  for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
    const Rgba8 color = i % 2 ? kBarColors[(first_color + i / 2) % 6].rgba : kWall;
    const Vec3d a = at(lines[i].first, -half_v), b = at(lines[i + 1].first, -half_v);
    const Vec3d c = at(lines[i + 1].second, half_v), d = at(lines[i].second, half_v);
    out.push_back(flat_triangle(a, b, c, color));
    out.push_back(flat_triangle(a, c, d, color));
  }
}

// The room (plain, or with stripes painted on its walls and floor) and, in the
// plain room, the bars (see the file comment).
std::unique_ptr<Scene> make_scene(bool painted) {
  auto scene = std::make_unique<Scene>();
  std::vector<Triangle> room;
  const double turn = 17 * kDegree;
  const Vec3d centre = kEye + Vec3d{1.3, -0.9, 2.4}, z{0, 0, 1};
  const Vec3d ex{std::cos(turn), std::sin(turn), 0}, ey{-std::sin(turn), std::cos(turn), 0};
  if (!painted) {
    add_box(room, centre, {ex, ey, z}, {30, 30, 10}, kWall);
    scene->source.add(chunk_from_triangles(1, room));
  } else {
    // Walls (near-vertical stripes 3.3 m apart), floor (stripes 1.7 m apart),
    // plain ceiling. Each plane reaches 0.5 m through the planes it meets, so
    // that the stripes' vertices on a plane's edge make no T-junctions there
    // (the sampler's rasteriser would leave pinholes in the cube faces).
    add_painted_plane(room, centre + ex * 30, ey, z, 30.5, 10.5, 3.3, 4, 0);
    add_painted_plane(room, centre - ex * 30, ey, z, 30.5, 10.5, 3.3, -5, 1);
    add_painted_plane(room, centre + ey * 30, ex, z, 30.5, 10.5, 3.3, 6, 2);
    add_painted_plane(room, centre - ey * 30, ex, z, 30.5, 10.5, 3.3, -3.5, 3);
    add_painted_plane(room, centre - z * 10, ex, ey, 30.5, 30.5, 1.7, 8, 4);
    add_painted_plane(room, centre + z * 10, ex, ey, 30.5, 30.5, 0, 0, 0);
    scene->source.add(chunk_from_triangles(1, room));
    return scene;
  }
  const double floor = kEye.z + 2.4 - 10, ceiling = kEye.z + 2.4 + 10;
  const double distances[5] = {5, 7.5, 11, 15, 20};
  const double widths[5] = {0.03, 0.05, 0.04, 0.07, 0.09};  // metres: about 1.5 to 2.3 px of a 512 face
  std::int64_t id = 2;
  // Vertical bars every 30 degrees of azimuth, floor to ceiling (and through both).
  for (int k = 0; k < 12; ++k) {
    const double azimuth = (11 + 30 * k) * kDegree, d = distances[k % 5], w = widths[(k + 2) % 5];
    const Vec3d radial{std::cos(azimuth), std::sin(azimuth), 0}, tangent{-std::sin(azimuth), std::cos(azimuth), 0};
    const Vec3d centre{kEye.x + d * radial.x, kEye.y + d * radial.y, 0.5 * (floor + ceiling)};
    // Tilted a few degrees sideways (the slanted-edge method): along the bar
    // its edges cross the pixel grid at every phase, so the scanline average
    // measures placement rather than one phase's rounding.
    const double tilt = (k % 2 ? 3.0 + 0.7 * k : -2.5 - 0.6 * k) * kDegree;
    const Vec3d axis = Vec3d{0, 0, std::cos(tilt)} + tangent * std::sin(tilt);
    const Vec3d across = tangent * std::cos(tilt) - Vec3d{0, 0, std::sin(tilt)};
    std::vector<Triangle> t;
    add_box(t, centre, {across, radial, axis}, {w / 2, w / 2, 0.5 * (ceiling - floor) / std::cos(tilt)},
            kBarColors[k % 6].rgba);
    scene->source.add(chunk_from_triangles(id++, t));
  }
  // Horizontal bars along the tangent, spanning +-40 degrees of azimuth, at
  // elevations between 13 and 20 degrees above and below the eye.
  const double elevations[4] = {14, -13, 19, -18};
  for (int k = 0; k < 8; ++k) {
    const double azimuth = (26 + 45 * k) * kDegree, d = distances[(k + 1) % 5], w = widths[(k + 4) % 5];
    const double elevation = elevations[k % 4] * kDegree;
    const Vec3d radial{std::cos(azimuth), std::sin(azimuth), 0}, tangent{-std::sin(azimuth), std::cos(azimuth), 0};
    const Vec3d centre = kEye + radial * d + Vec3d{0, 0, d * std::tan(elevation)};
    std::vector<Triangle> t;
    add_box(t, centre, {tangent, radial, Vec3d{0, 0, 1}}, {d * std::tan(40 * kDegree), w / 2, w / 2},
            kBarColors[(k + 3) % 6].rgba);
    scene->source.add(chunk_from_triangles(id++, t));
  }
  return scene;
}

// What the far field goes through before it is drawn.
enum class Stage {
  dense,       // build_depth_meshes, raw face image
  simplified,  // + simplify_face_mesh (default params)
  encoded,     // + encode/decode of the mesh and of the image (PNG: lossless colour, so only geometry moves)
  coarse,      // the same with 12 position bits: the quantisation step a ~1 km model gets at 16 bits
};

// Unlit: the bar weights measure colour steps from the wall's grey, which
// lighting would scale differently per surface orientation (the light model
// is tested in test_shading.cpp).
ShadingLights unlit_lights() {
  ShadingParams p;
  p.mode = ShadingMode::unlit;
  return shading_lights(p, Vec3d{0, 0, 1});
}

struct Pipeline {
  std::shared_ptr<GlContext> context{create_gl_context(GlBackend::osmesa, 1, 1)};
  ChunkRenderer chunks{std::make_unique<SharedGlContext>(context)};
  TdmRenderer tdm{context};
  Pipeline() { chunks.set_shading(unlit_lights()); }
};

std::vector<std::uint64_t> upload_impostor(Pipeline& gl, const CubeSample& sample, Stage stage) {
  const std::array<FaceMesh, kCubeFaces> dense = build_depth_meshes(sample, DepthMeshParams{});
  std::vector<std::uint64_t> handles;
  for (int f = 0; f < kCubeFaces; ++f) {
    const CubeFace& face = sample.faces[f];
    FaceMesh mesh = dense[f];
    DecodedImage image{face.size, face.size, face.color};
    if (stage != Stage::dense) mesh = simplify_face_mesh(mesh, face.size, SimplifyParams{}).mesh;
    if (stage == Stage::encoded || stage == Stage::coarse) {
      MeshEncodeParams mp;
      if (stage == Stage::coarse) mp.position_bits = 12;
      mesh = decode_face_mesh(encode_face_mesh(mesh, mp));
      ImageEncodeParams png;
      png.format = "png";
      image = decode_image(encode_image(face.color, face.size, face.size, png));
    }
    handles.push_back(gl.tdm.upload(mesh, image, sample.eye));
  }
  return handles;
}

struct Frame {
  int width = 0, height = 0;
  std::vector<Rgba8> color;
  std::vector<float> depth;
  const Rgba8& at(int x, int y) const { return color[std::size_t(y) * width + x]; }
};

// The ground truth, antialiased: drawn at kTruthSupersample times the
// resolution and box-filtered, so a pixel's colour is the coverage-weighted
// blend and a bar's centroid and width are exact to ~1/kTruthSupersample px
// even where its edges are parallel to the pixel grid.
constexpr int kTruthSupersample = 8;

Frame draw_truth(Pipeline& gl, const Scene& scene, const RenderCamera& camera, int width, int height) {
  const int f = kTruthSupersample, big_width = width * f;
  std::vector<Rgba8> color;
  std::vector<float> depth;
  const std::vector<std::int64_t> ids = chunks_in_view(camera, scene.source);
  gl.chunks.begin_frame(big_width, height * f);
  gl.chunks.draw(camera, Box3d{}, ids, [&](std::int64_t id) { return scene.source.load(id); });
  gl.chunks.read_frame(color, depth);
  Frame out{width, height, std::vector<Rgba8>(std::size_t(width) * height), {}};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      unsigned sum[3] = {0, 0, 0};
      for (int dy = 0; dy < f; ++dy)
        for (int dx = 0; dx < f; ++dx) {
          const Rgba8& c = color[std::size_t(y * f + dy) * big_width + std::size_t(x * f + dx)];
          sum[0] += c.r, sum[1] += c.g, sum[2] += c.b;
        }
      const auto average = [&](unsigned s) { return std::uint8_t((s + f * f / 2) / (f * f)); };
      out.color[std::size_t(y) * width + x] = {average(sum[0]), average(sum[1]), average(sum[2]), 255};
    }
  return out;
}

Frame draw_impostor(Pipeline& gl, const std::vector<std::uint64_t>& handles, const RenderCamera& camera, int width,
                    int height) {
  Frame f{width, height, {}, {}};
  gl.chunks.begin_frame(width, height);
  gl.tdm.draw(camera, gl.chunks.reversed_z(), handles);
  gl.chunks.read_frame(f.color, f.depth);
  return f;
}

// One bar seen in one view: the mean over its clean scanlines of the
// impostor's centroid minus the truth's (pixels, along +x across a vertical
// bar, +y across a horizontal one) and of the width difference.
struct BarMeasure {
  int view = 0, color = 0, lines = 0;
  bool vertical = true;
  double offset = 0, width_difference = 0, truth_width = 0;
};

struct Measures {
  std::vector<BarMeasure> bars;
  double squared_error = 0;  // over R, G, B of the pixels in the scanline windows
  std::size_t samples = 0;
  std::size_t cracks = 0;  // impostor pixels nothing was drawn on (the closed room covers every direction)
  double psnr_db() const { return samples ? 10 * std::log10(255.0 * 255.0 / (squared_error / samples)) : 0; }
};

constexpr int kWindowMargin = 5;     // pixels each side of the truth's run of bar pixels
constexpr int kMaxBarWidth = 16;     // longer runs are bars seen lengthwise, not across
constexpr int kCleanNeighbours = 3;  // scanlines each side that must be clean too (away from bar ends and crossings)

// Whether truth pixel `c` is a blend of the wall and bar colour `b` only.
bool wall_or_bar(const BarColor& b, const Rgba8& c) {
  const int v[3] = {c.r, c.g, c.b};
  for (int ch = 0; ch < 3; ++ch)
    if (ch != b.channel && v[ch] != 128) return false;
  return b.sign * (v[b.channel] - 128) >= 0;
}

// Measures every bar crossing of one view. A bar is found by its colour in the
// (antialiased) truth: along each scanline one run of at most kMaxBarWidth
// pixels with that colour's weight, inside a window of wall and bar blends.
void measure_view(const Frame& truth, const Frame& impostor, int view, Measures& out) {
  for (int color_index = 0; color_index < int(kBarColors.size()); ++color_index)
    for (bool vertical : {true, false}) {
      const BarColor& color = kBarColors[color_index];
      // Scanlines run along x across a vertical bar; `along` indexes pixels in a scanline.
      const int lines = vertical ? truth.height : truth.width, along = vertical ? truth.width : truth.height;
      const auto pixel = [&](const Frame& f, int line, int k) -> const Rgba8& {
        return vertical ? f.at(k, line) : f.at(line, k);
      };
      struct Window {
        bool clean = false;
        int lo = 0, hi = 0;
      };
      std::vector<Window> windows(lines);
      for (int line = 0; line < lines; ++line) {
        int first = -1, last = -1, runs = 0;
        for (int k = 0; k < along; ++k)
          if (bar_weight(color, pixel(truth, line, k)) > 0) {
            if (first < 0 || last != k - 1) ++runs;
            if (first < 0) first = k;
            last = k;
          }
        if (runs != 1 || last - first + 1 > kMaxBarWidth) continue;
        Window w{true, first - kWindowMargin, last + kWindowMargin};
        if (w.lo < 0 || w.hi >= along) continue;
        for (int k = w.lo; k <= w.hi && w.clean; ++k) w.clean = wall_or_bar(color, pixel(truth, line, k));
        windows[line] = w;
      }
      BarMeasure m;
      m.view = view;
      m.color = color_index;
      m.vertical = vertical;
      for (int line = kCleanNeighbours; line < lines - kCleanNeighbours; ++line) {
        bool clean = true;
        for (int d = -kCleanNeighbours; d <= kCleanNeighbours; ++d) clean = clean && windows[line + d].clean;
        if (!clean) continue;
        const Window& w = windows[line];
        double tw = 0, tx = 0, iw = 0, ix = 0;
        for (int k = w.lo; k <= w.hi; ++k) {
          const Rgba8 &t = pixel(truth, line, k), &i = pixel(impostor, line, k);
          const double a = bar_weight(color, t), c = bar_weight(color, i);
          tw += a, tx += a * k, iw += c, ix += c * k;
          for (int ch = 0; ch < 3; ++ch) {
            const double e = double((&t.r)[ch]) - double((&i.r)[ch]);
            out.squared_error += e * e;
          }
          out.samples += 3;
        }
        ++m.lines;
        m.truth_width += tw;
        m.width_difference += iw - tw;
        // A bar missing from the impostor counts as missing width, not as an offset.
        if (iw > 0.25) m.offset += ix / iw - tx / tw;
      }
      if (m.lines == 0) continue;
      m.offset /= m.lines;
      m.width_difference /= m.lines;
      m.truth_width /= m.lines;
      out.bars.push_back(m);
    }
}

struct View {
  double azimuth_deg, elevation_deg;
};
// Along cube axes, across face edges (45 degrees) and in between.
const std::vector<View> kViews = {{0, 0},    {45, 3},   {20, 6},   {63, -7},   {135, 9}, {200, -4},
                                  {251, 11}, {318, -9}, {100, 17}, {290, -16}, {170, 0}};

struct Summary {
  double mean_offset = 0, mean_abs_offset = 0, max_abs_offset = 0, mean_width_difference = 0, max_abs_width = 0;
  std::size_t bars = 0, lines = 0, cracks = 0;
  double psnr_db = 0;
};

// Writes `f` as a PNG (for a person looking at a failure; see run_views).
void write_png(const Frame& f, const std::filesystem::path& file) {
  ImageEncodeParams png;
  png.format = "png";
  const std::vector<std::uint8_t> bytes = encode_image(f.color, f.width, f.height, png);
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// With CELLBAKE_KEEP_TEST_DIRS set, the frames are written into `dir` as well.
Summary run_views(Pipeline& gl, const Scene& scene, const std::vector<std::uint64_t>& handles, int width, int height,
                  double fov_y_deg, const char* label, const test::TempDir& dir) {
  Measures all;
  for (std::size_t v = 0; v < kViews.size(); ++v) {
    const double a = kViews[v].azimuth_deg * kDegree, e = kViews[v].elevation_deg * kDegree;
    const Vec3d look = kEye + Vec3d{std::cos(a) * std::cos(e), std::sin(a) * std::cos(e), std::sin(e)};
    const RenderCamera camera = look_at_camera(kEye, look, {0, 0, 1}, fov_y_deg, width, height);
    const Frame truth = draw_truth(gl, scene, camera, width, height);
    const Frame impostor = draw_impostor(gl, handles, camera, width, height);
    measure_view(truth, impostor, static_cast<int>(v), all);
    for (const Rgba8& c : impostor.color) all.cracks += c.a == 0;
    if (std::getenv("CELLBAKE_KEEP_TEST_DIRS")) {
      write_png(truth, dir / ("view" + std::to_string(v) + "_truth.png"));
      write_png(impostor, dir / ("view" + std::to_string(v) + "_impostor.png"));
    }
  }
  Summary s;
  for (const BarMeasure& m : all.bars) {
    s.mean_offset += m.offset * m.lines;
    s.mean_abs_offset += std::abs(m.offset);
    s.max_abs_offset = std::max(s.max_abs_offset, std::abs(m.offset));
    s.mean_width_difference += m.width_difference * m.lines;
    s.max_abs_width = std::max(s.max_abs_width, std::abs(m.width_difference));
    s.lines += static_cast<std::size_t>(m.lines);
    if (std::getenv("CELLBAKE_REGISTRATION_VERBOSE"))
      std::printf("  %s view %2d colour %d (%s): %4d lines, width %.2f px, offset %+.3f px, width diff %+.3f px\n",
                  label, m.view, m.color, m.vertical ? "v" : "h", m.lines, m.truth_width, m.offset,
                  m.width_difference);
  }
  s.bars = all.bars.size();
  if (s.lines > 0) s.mean_offset /= s.lines, s.mean_width_difference /= s.lines;
  if (s.bars > 0) s.mean_abs_offset /= s.bars;
  s.psnr_db = all.psnr_db();
  s.cracks = all.cracks;
  std::printf(
      "%s: %zu bar views, %zu scanlines: mean offset %+.3f px, mean |bar offset| %.3f px (max %.3f), mean width diff "
      "%+.3f px (max |bar| %.3f), bar-region PSNR %.2f dB, %zu crack pixels\n",
      label, s.bars, s.lines, s.mean_offset, s.mean_abs_offset, s.max_abs_offset, s.mean_width_difference,
      s.max_abs_width, s.psnr_db, s.cracks);
  return s;
}

struct Case {
  int face_size, supersample;
  Stage stage;
  bool painted;  // stripes painted on the room instead of bars in front of it
};

std::string stage_name(Stage s) {
  switch (s) {
    case Stage::dense: return "dense";
    case Stage::simplified: return "simplified";
    case Stage::encoded: return "encoded";
    default: return "encoded12bit";
  }
}

std::string case_name(const Case& c) {
  return std::string(c.painted ? "painted" : "bars") + "_face" + std::to_string(c.face_size) + "_ss" +
         std::to_string(c.supersample) + "_" + stage_name(c.stage);
}

class Registration : public ::testing::TestWithParam<Case> {};

TEST_P(Registration, ImpostorAtTheSamplePointPutsEdgesWhereTheTruthDoes) {
  test::TempDir dir;  // frames go here with CELLBAKE_KEEP_TEST_DIRS
  const Case c = GetParam();
  const auto scene = make_scene(c.painted);
  Pipeline gl;
  SampleParams sp;
  sp.face_size = c.face_size;
  sp.supersample = c.supersample;
  const CubeSample sample = sample_cube(kEye, Box3d::cube(kEye, 0.5), sp, scene->source, gl.chunks);
  const std::vector<std::uint64_t> handles = upload_impostor(gl, sample, c.stage);
  const std::string label = case_name(c);
  // About the faces' angular resolution at the image centre (90 degrees over
  // face_size pixels), but not equal, and not square.
  const int height = c.face_size * 3 / 5 + 7, width = height * 4 / 3 + 3;
  const Summary s = run_views(gl, *scene, handles, width, height, 56.0, label.c_str(), dir);
  ASSERT_GT(s.bars, 30u);
  // Over all bars: no systematic shift, no systematic thinning or thickening.
  EXPECT_LT(std::abs(s.mean_offset), 0.1) << label;
  EXPECT_LT(std::abs(s.mean_width_difference), 0.2) << label;
  // Each bar on its own (what a viewer sees as "a pixel off"): a point-sampled
  // face (supersample 1) knows a bar's coverage only to a face pixel per
  // scanline, so bars thinner than a pixel wander more there.
  EXPECT_LT(s.mean_abs_offset, 0.15) << label;
  EXPECT_LT(s.max_abs_offset, c.supersample == 1 ? 1.25 : 0.75) << label;
  EXPECT_GT(s.psnr_db, c.supersample == 1 ? 26.5 : 29.0) << label;
  EXPECT_EQ(s.cracks, 0u) << label;
}

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (bool painted : {false, true})
    for (Stage stage : {Stage::dense, Stage::simplified, Stage::encoded, Stage::coarse})
      for (int face_size : {256, 512})
        for (int supersample : {1, 2}) cases.push_back({face_size, supersample, stage, painted});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Faces, Registration, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return case_name(info.param); });

}  // namespace
}  // namespace cellbake
