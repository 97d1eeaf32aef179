// Simplification of dense depth meshes built from analytic scenes: flat faces
// collapse to a couple of triangles, the error bound holds, coverage is kept,
// nothing flips, neighbouring faces keep identical border vertices, output is
// deterministic, the triangle cap relaxes the bound and says so.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <tuple>

#include "pipeline/scenes/depth_mesh_analytic_scene.h"
#include "stages/depth_mesh.h"
#include "stages/simplify/simplify.h"

namespace cellbake {
namespace {

using PositionKey = std::tuple<float, float, float>;

std::set<PositionKey> border_positions(const FaceMesh& m) {
  std::set<PositionKey> out;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const Uv uv = m.uvs[v];
    if (uv.u == 0.0f || uv.v == 0.0f || uv.u == 1.0f || uv.v == 1.0f)
      out.insert({m.positions[v].x, m.positions[v].y, m.positions[v].z});
  }
  return out;
}

// Outlines within half a pixel (the straightening bound), depth within the
// bound, no flips, no overlaps.
void expect_bounds(const SimplifyResult& r, double bound, int face) {
  EXPECT_LE(r.achieved.max_depth_error_relative, bound * (1 + 1e-6) + 1e-7) << "face " << face;
  EXPECT_LE(r.achieved.max_boundary_error_px, SimplifyParams{}.boundary_error_px + 1e-9) << "face " << face;
  EXPECT_EQ(r.achieved.flipped_triangles, 0u) << "face " << face;
  EXPECT_EQ(r.achieved.overlapping_samples, 0u) << "face " << face;
  EXPECT_EQ(r.triangles_out, r.mesh.triangle_count());
  EXPECT_LE(r.outline_triangles, r.triangles_out) << "face " << face;  // a lower bound
}

AnalyticScene cluttered_room() {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 10.0));  // the room, seen from inside
  scene.boxes.push_back({{2, -1, -3}, {3, 1, 0}});
  scene.boxes.push_back({{-6, 3, -10}, {-4, 5, 2}});
  scene.boxes.push_back({{-2, -7, 1}, {1, -5, 3}});
  scene.cylinders.push_back({4, 4, 0.4, -10, 10});
  scene.cylinders.push_back({-3, -2, 1.0, -10, -1});
  scene.cylinders.push_back({1.5, 6, 0.15, -10, 10});  // a thin pipe
  return scene;
}

TEST(Simplify, BoxFacesSeenFromTheCentreBecomeTwoTriangles) {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 1.0));
  const int n = 64;
  const auto dense = build_depth_meshes(raycast_analytic_scene(scene, {0, 0, 0}, n), DepthMeshParams{});
  std::array<SimplifyResult, kCubeFaces> out;
  for (int f = 0; f < kCubeFaces; ++f) {
    out[f] = simplify_face_mesh(dense[f], n, SimplifyParams{});
    EXPECT_EQ(out[f].triangles_in, std::size_t(2 * n * n));
    EXPECT_LE(out[f].triangles_out, 8u) << "face " << f;
    EXPECT_LT(out[f].achieved.max_depth_error_relative, 1e-6);
    expect_bounds(out[f], 1e-6, f);
    EXPECT_FALSE(out[f].cap_forced_larger_error);
  }
  // Adjacent faces share their two cube-corner vertices exactly.
  for (int a = 0; a < kCubeFaces; ++a)
    for (int b = a + 1; b < kCubeFaces; ++b) {
      if (a / 2 == b / 2) continue;
      const auto pa = border_positions(out[a].mesh), pb = border_positions(out[b].mesh);
      std::vector<PositionKey> common;
      std::set_intersection(pa.begin(), pa.end(), pb.begin(), pb.end(), std::back_inserter(common));
      EXPECT_EQ(common.size(), 2u) << "faces " << a << ", " << b;
    }
}

TEST(Simplify, PlaneSeenFromAboveBecomesAHandfulOfTriangles) {
  AnalyticScene scene;
  scene.boxes.push_back({{-1000, -1000, -5}, {1000, 1000, 0}});  // ground, top at z = 0
  const int n = 64;
  const auto dense = build_depth_meshes(raycast_analytic_scene(scene, {0.3, -0.2, 2}, n), DepthMeshParams{});
  const SimplifyResult down = simplify_face_mesh(dense[5], n, SimplifyParams{});  // -Z
  EXPECT_LE(down.triangles_out, 8u);
  expect_bounds(down, SimplifyParams{}.depth_error_relative, 5);
  // A side face sees the same plane obliquely (exactly planar in (x, y, 1/z)),
  // plus a grazing horizon band cut into single pixels by skins at this low
  // resolution: well under half of the input.
  const SimplifyResult side = simplify_face_mesh(dense[0], n, SimplifyParams{});
  EXPECT_LT(side.triangles_out * 2, side.triangles_in);
  expect_bounds(side, SimplifyParams{}.depth_error_relative, 0);
}

TEST(Simplify, ClutteredRoomKeepsTheBoundCoverageAndCrackFreeBorders) {
  const int n = 96;
  const auto dense = build_depth_meshes(raycast_analytic_scene(cluttered_room(), {0.35, 0.2, -0.15}, n),
                                        DepthMeshParams{});
  SimplifyParams params;
  params.depth_error_relative = 0.005;
  std::array<SimplifyResult, kCubeFaces> out;
  std::size_t in_total = 0, out_total = 0;
  for (int f = 0; f < kCubeFaces; ++f) {
    out[f] = simplify_face_mesh(dense[f], n, params);
    expect_bounds(out[f], params.depth_error_relative, f);
    in_total += out[f].triangles_in;
    out_total += out[f].triangles_out;
  }
  EXPECT_LT(out_total * 4, in_total);
  // A border vertex both dense faces share is kept by both simplified faces or by neither.
  for (int a = 0; a < kCubeFaces; ++a)
    for (int b = a + 1; b < kCubeFaces; ++b) {
      if (a / 2 == b / 2) continue;
      const auto da = border_positions(dense[a]), db = border_positions(dense[b]);
      const auto sa = border_positions(out[a].mesh), sb = border_positions(out[b].mesh);
      std::vector<PositionKey> shared;
      std::set_intersection(da.begin(), da.end(), db.begin(), db.end(), std::back_inserter(shared));
      ASSERT_GT(shared.size(), 0u);
      for (const PositionKey& p : shared) EXPECT_EQ(sa.count(p), sb.count(p)) << "faces " << a << ", " << b;
    }
}

TEST(Simplify, IsDeterministic) {
  const int n = 64;
  const auto dense = build_depth_meshes(raycast_analytic_scene(cluttered_room(), {0, 0, 0}, n), DepthMeshParams{});
  for (int f : {0, 3}) {
    const SimplifyResult a = simplify_face_mesh(dense[f], n, SimplifyParams{});
    const SimplifyResult b = simplify_face_mesh(dense[f], n, SimplifyParams{});
    EXPECT_EQ(a.mesh.positions, b.mesh.positions);
    EXPECT_EQ(a.mesh.uvs, b.mesh.uvs);
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
  }
}

// The cluttered room's dense faces of n^2 pixels, seen from off its centre.
std::array<FaceMesh, kCubeFaces> off_centre_room_faces(int n) {
  return build_depth_meshes(raycast_analytic_scene(cluttered_room(), {0.2, -0.1, 0.1}, n), DepthMeshParams{});
}

// The default parameters, and a cap of 16 triangles that every face exceeds.
std::array<SimplifyParams, 2> default_and_capped_params() {
  SimplifyParams capped;
  capped.max_triangles = 16;
  return {SimplifyParams{}, capped};
}

TEST(Simplify, TwoStepsGiveTheSameResultAndBoundItFirst) {
  // FaceSimplification (outline triangulation, then refinement) returns
  // exactly simplify_face_mesh's result, its early outline count bounds it,
  // also for a face over the cap and for a borrowed or an owned dense mesh.
  const int n = 64;
  const auto dense = off_centre_room_faces(n);
  for (const SimplifyParams& params : default_and_capped_params())
    for (int f = 0; f < kCubeFaces; ++f) {
      SCOPED_TRACE(testing::Message() << "face " << f << " cap " << params.max_triangles);
      const SimplifyResult whole = simplify_face_mesh(dense[std::size_t(f)], n, params);
      FaceSimplification borrowed(dense[std::size_t(f)], n, params);
      FaceSimplification owned(FaceMesh(dense[std::size_t(f)]), n, params);
      EXPECT_EQ(borrowed.outline_triangles(), whole.outline_triangles);
      EXPECT_EQ(owned.outline_triangles(), whole.outline_triangles);
      EXPECT_LE(borrowed.outline_triangles(), whole.triangles_out);
      FaceSimplification moved = std::move(owned);
      for (FaceSimplification* step : {&borrowed, &moved}) {
        const SimplifyResult r = std::move(*step).finish();
        EXPECT_EQ(r.mesh.positions, whole.mesh.positions);
        EXPECT_EQ(r.mesh.uvs, whole.mesh.uvs);
        EXPECT_EQ(r.mesh.indices, whole.mesh.indices);
        EXPECT_EQ(r.depth_error_bound_used, whole.depth_error_bound_used);
        EXPECT_EQ(r.achieved.max_depth_error_relative, whole.achieved.max_depth_error_relative);
        EXPECT_THROW(std::move(*step).finish(), std::logic_error);
        EXPECT_EQ(step->outline_triangles(), whole.outline_triangles);
      }
    }
}

// The same error figures, field by field.
void expect_same_error(const SimplifyError& a, const SimplifyError& b) {
  EXPECT_EQ(a.max_depth_error_relative, b.max_depth_error_relative);
  EXPECT_EQ(a.max_boundary_error_px, b.max_boundary_error_px);
  EXPECT_EQ(a.uncovered_samples, b.uncovered_samples);
  EXPECT_EQ(a.spurious_samples, b.spurious_samples);
  EXPECT_EQ(a.flipped_triangles, b.flipped_triangles);
  EXPECT_EQ(a.overlapping_samples, b.overlapping_samples);
}

TEST(Simplify, ARulerMeasuresTheResultLaterWithTheSameFigures) {
  // finish(ruler) returns finish()'s mesh unmeasured, and the ruler measures
  // it as finish() and measure_simplification_error do, for owned and
  // borrowed dense meshes, a face over the cap and one too small to simplify.
  for (const int n : {64, 2}) {
    const auto dense = off_centre_room_faces(n);
    for (const SimplifyParams& params : default_and_capped_params())
      for (int f = 0; f < kCubeFaces; ++f) {
        SCOPED_TRACE(testing::Message() << "size " << n << " face " << f << " cap " << params.max_triangles);
        const FaceMesh& face = dense[std::size_t(f)];
        const SimplifyResult whole = simplify_face_mesh(face, n, params);
        SimplifyRuler owned_ruler, borrowed_ruler;
        EXPECT_FALSE(owned_ruler);
        EXPECT_THROW(owned_ruler.measure(whole.mesh), std::logic_error);
        const SimplifyResult owned = FaceSimplification(FaceMesh(face), n, params).finish(owned_ruler);
        const SimplifyResult borrowed = FaceSimplification(face, n, params).finish(borrowed_ruler);
        for (const SimplifyResult* r : {&owned, &borrowed}) {
          EXPECT_EQ(r->mesh.positions, whole.mesh.positions);
          EXPECT_EQ(r->mesh.indices, whole.mesh.indices);
          expect_same_error(r->achieved, SimplifyError{});
        }
        ASSERT_TRUE(owned_ruler);
        SimplifyRuler moved = std::move(owned_ruler);
        expect_same_error(moved.measure(owned.mesh), whole.achieved);
        expect_same_error(borrowed_ruler.measure(borrowed.mesh), whole.achieved);
        expect_same_error(moved.measure(owned.mesh), measure_simplification_error(face, owned.mesh, n));
      }
  }
}

// Boundary edges (used by one triangle) of `m` in pixels, lower vertex first,
// and whether each lies on a side of the n-pixel face square.
struct PixelSegment {
  double ax, ay, bx, by;
  bool on_face_side;
};
std::vector<PixelSegment> boundary_segments(const FaceMesh& m, int n) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = m.indices[t + e], b = m.indices[t + (e + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<PixelSegment> out;
  for (const auto& [edge, count] : uses) {
    if (count != 1) continue;
    const Uv a = m.uvs[edge.first], b = m.uvs[edge.second];
    PixelSegment s{double(a.u) * n, double(a.v) * n, double(b.u) * n, double(b.v) * n, false};
    auto same_side = [&](double p, double q) {
      return (std::abs(p) < 1e-4 && std::abs(q) < 1e-4) || (std::abs(p - n) < 1e-4 && std::abs(q - n) < 1e-4);
    };
    s.on_face_side = same_side(s.ax, s.bx) || same_side(s.ay, s.by);
    out.push_back(s);
  }
  return out;
}

// Brute force of max_boundary_error_px: every segment off the face sides
// sampled every 1/8 px (its ends exactly), each sample's distance to every
// segment of the other mesh's boundary, capped at 64 px; the larger of both ways.
double brute_force_boundary_error(const FaceMesh& dense, const FaceMesh& simplified, int n) {
  const std::vector<PixelSegment> d = boundary_segments(dense, n), s = boundary_segments(simplified, n);
  auto distance = [](double px, double py, const PixelSegment& g) {
    const double dx = g.bx - g.ax, dy = g.by - g.ay, qx = px - g.ax, qy = py - g.ay;
    const double len2 = dx * dx + dy * dy;
    const double t = len2 > 0 ? std::clamp((qx * dx + qy * dy) / len2, 0.0, 1.0) : 0.0;
    const double ex = qx - t * dx, ey = qy - t * dy;
    return std::sqrt(ex * ex + ey * ey);
  };
  auto directed = [&](const std::vector<PixelSegment>& from, const std::vector<PixelSegment>& to) {
    double worst = 0;
    for (const PixelSegment& g : from) {
      if (g.on_face_side) continue;
      const int steps = std::max(1, int(std::ceil(std::hypot(g.bx - g.ax, g.by - g.ay) * 8)));
      for (int k = 0; k <= steps; ++k) {
        const double t = double(k) / steps;
        const double x = k == 0 ? g.ax : k == steps ? g.bx : g.ax + t * (g.bx - g.ax);
        const double y = k == 0 ? g.ay : k == steps ? g.by : g.ay + t * (g.by - g.ay);
        double best = 64;
        for (const PixelSegment& h : to) best = std::min(best, distance(x, y, h));
        worst = std::max(worst, best);
      }
    }
    return worst;
  };
  return std::max(directed(s, d), directed(d, s));
}

TEST(Simplify, OutlineErrorIsTheLargestDistanceOfEverySampleBothWays) {
  // The measurement's pruning (distance grid, run bounds, queries stopped
  // within the running max, edges both outlines share) gives exactly the
  // brute-force figure, at the default half-pixel outlines and at exact ones.
  const int n = 128;  // a power of two: uv * n are the exact lattice points
  const auto dense = off_centre_room_faces(n);
  int moved = 0;
  for (const double outline_px : {0.5, 0.0})
    for (int f = 0; f < kCubeFaces; ++f) {
      SCOPED_TRACE(testing::Message() << "face " << f << " outline bound " << outline_px);
      SimplifyParams params;
      params.boundary_error_px = outline_px;
      const FaceMesh& face = dense[std::size_t(f)];
      const SimplifyResult r = simplify_face_mesh(face, n, params);
      EXPECT_EQ(r.achieved.max_boundary_error_px, brute_force_boundary_error(face, r.mesh, n));
      moved += r.achieved.max_boundary_error_px > 0.1;
    }
  EXPECT_GT(moved, 0);  // some outline did move, so the figure was measured
}

TEST(Simplify, TighterBoundKeepsMoreTriangles) {
  const int n = 64;
  const auto dense = build_depth_meshes(raycast_analytic_scene(cluttered_room(), {0, 0, 0}, n), DepthMeshParams{});
  SimplifyParams loose, tight;
  loose.depth_error_relative = 0.02;
  tight.depth_error_relative = 0.0005;
  std::size_t loose_total = 0, tight_total = 0;
  for (int f = 0; f < kCubeFaces; ++f) {
    const SimplifyResult a = simplify_face_mesh(dense[f], n, loose);
    const SimplifyResult b = simplify_face_mesh(dense[f], n, tight);
    expect_bounds(a, loose.depth_error_relative, f);
    expect_bounds(b, tight.depth_error_relative, f);
    loose_total += a.triangles_out;
    tight_total += b.triangles_out;
  }
  EXPECT_LT(loose_total, tight_total);
}

TEST(Simplify, TriangleCapRelaxesTheInteriorBoundAndReportsIt) {
  // A wide column close to the eye: curved, so the triangle count follows the bound.
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 10.0));
  scene.cylinders.push_back({4, 0, 2.5, -10, 10});
  const int n = 64;
  const auto dense = build_depth_meshes(raycast_analytic_scene(scene, {0, 0, 0}, n), DepthMeshParams{});
  SimplifyParams params;
  params.depth_error_relative = 0.0005;
  const SimplifyResult free_run = simplify_face_mesh(dense[0], n, params);
  ASSERT_FALSE(free_run.cap_forced_larger_error);
  params.max_triangles = free_run.triangles_out * 3 / 4;
  const SimplifyResult capped = simplify_face_mesh(dense[0], n, params);
  EXPECT_TRUE(capped.cap_forced_larger_error);
  EXPECT_GT(capped.depth_error_bound_used, params.depth_error_relative);
  EXPECT_LE(capped.triangles_out, params.max_triangles);
  EXPECT_GT(capped.achieved.max_depth_error_relative, params.depth_error_relative);
  expect_bounds(capped, capped.depth_error_bound_used, 0);
}

TEST(Simplify, OutlineDominatedFaceOverTheCapStopsAtTheLooserBound) {
  // Pixel-exact outlines (boundary_error_px = 0) cannot be simplified, so the
  // cap is out of reach: refinement stops once every miss is within
  // max_depth_error_factor times the bound, with fewer triangles than uncapped.
  const int n = 64;
  const auto dense = build_depth_meshes(raycast_analytic_scene(cluttered_room(), {0, 0, 0}, n), DepthMeshParams{});
  SimplifyParams params;
  params.depth_error_relative = 0.0005;
  params.boundary_error_px = 0;
  params.max_triangles = std::size_t(1) << 40;
  const SimplifyResult free_run = simplify_face_mesh(dense[2], n, params);
  EXPECT_LT(free_run.achieved.max_boundary_error_px, 1e-6);
  EXPECT_EQ(free_run.achieved.uncovered_samples, 0u);
  EXPECT_EQ(free_run.achieved.spurious_samples, 0u);
  expect_bounds(free_run, params.depth_error_relative, 2);
  params.max_triangles = free_run.triangles_out / 10;
  const SimplifyResult capped = simplify_face_mesh(dense[2], n, params);
  EXPECT_GT(capped.triangles_out, params.max_triangles);
  EXPECT_LT(capped.triangles_out, free_run.triangles_out);
  EXPECT_LE(capped.depth_error_bound_used, params.depth_error_relative * params.max_depth_error_factor);
  EXPECT_LT(capped.achieved.max_boundary_error_px, 1e-6);
  expect_bounds(capped, capped.depth_error_bound_used, 2);
}

// Dozens of thin vertical pipes below a ceiling, seen from underneath (the +Z
// face): they appear as slanted radial bands 2-6 px wide at 512^2, their
// outlines pixel staircases.
AnalyticScene pipe_array() {
  AnalyticScene scene;
  scene.boxes.push_back({{-60, -60, 30}, {60, 60, 31}});  // the ceiling
  for (int k = 0; k < 40; ++k) {
    const double angle = 0.157 * k + 0.03 * (k % 3), rho = 3.0 + 0.1 * (k % 11);
    // Width in pixels 2 r / z * 256 for z in [8, 29]: about 6 px down to 2 px.
    scene.cylinders.push_back({rho * std::cos(angle), rho * std::sin(angle), 0.1, 8.0 + 0.1 * (k % 5), 29.0});
  }
  return scene;
}

TEST(Simplify, PipeArrayMeetsTheTriangleCapWithinTheBounds) {
  const int n = 512;
  const CubeSample sample = raycast_analytic_scene(pipe_array(), {0, 0, 0}, n);
  const auto dense = build_depth_meshes(sample, DepthMeshParams{});
  const SimplifyParams params;  // 1 % depth, 0.5 px outlines, 10,000 triangles
  const SimplifyResult r = simplify_face_mesh(dense[4], n, params);
  EXPECT_GT(r.triangles_in, 400000u);
  EXPECT_LE(r.triangles_out, params.max_triangles);
  EXPECT_LE(r.depth_error_bound_used, 4 * params.depth_error_relative);
  expect_bounds(r, r.depth_error_bound_used, 4);
  EXPECT_GT(r.achieved.max_boundary_error_px, 0.2);  // the outlines did move
  // Straightening pays: pixel-exact outlines need more triangles at the same bound.
  SimplifyParams free_params = params, exact = params;
  free_params.max_triangles = std::size_t(1) << 40;
  exact.max_triangles = std::size_t(1) << 40;
  exact.boundary_error_px = 0;
  const SimplifyResult straightened = simplify_face_mesh(dense[4], n, free_params);
  const SimplifyResult pixel_exact = simplify_face_mesh(dense[4], n, exact);
  expect_bounds(straightened, params.depth_error_relative, 4);
  EXPECT_LT(pixel_exact.achieved.max_boundary_error_px, 1e-6);
  EXPECT_LT(straightened.triangles_out * 11, pixel_exact.triangles_out * 10);
}

// Every face of the cube at planar depth 10, with islands of one to four
// pixels at depths 3-6 (skins all round) scattered over the +X face.
CubeSample tiny_islands_sample(int n) {
  CubeSample sample;
  for (CubeFace& f : sample.faces) {
    f.size = n;
    f.color.assign(std::size_t(n) * n, Rgba8{128, 128, 128, 255});
    f.depth.assign(std::size_t(n) * n, 10.0f);
  }
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pos(2, n - 4), shape(0, 15);
  std::vector<float>& depth = sample.faces[0].depth;
  for (int k = 0; k < n * n / 8; ++k) {  // dense enough that islands touch and nest
    const int x = pos(rng), y = pos(rng), bits = shape(rng) | 1;  // pixels of a 2x2 block, the first always set
    const float d = 3.0f + 0.5f * float(k % 7);
    for (int b = 0; b < 4; ++b)
      if (bits & (1 << b)) depth[std::size_t(y + b / 2) * n + x + b % 2] = d;
  }
  return sample;
}

TEST(Simplify, TinyIslandsKeepTheirOwnTrianglesWithinHalfAPixel) {
  // Straightening a one-to-four-pixel island's outline can leave a triangle
  // whose centroid pixel belongs to the surface around it; the island must
  // still be drawn with its own depths, not dropped (a hole) or given the
  // surrounding surface.
  const int n = 64;
  const auto dense = build_depth_meshes(tiny_islands_sample(n), DepthMeshParams{});
  const SimplifyResult r = simplify_face_mesh(dense[0], n, SimplifyParams{});
  expect_bounds(r, SimplifyParams{}.depth_error_relative, 0);
  // Each island keeps about its area: coverage moves only with the outlines.
  EXPECT_LT(r.achieved.uncovered_samples + r.achieved.spurious_samples, std::size_t(n) * n / 20);
}

// Random boxes and pipes around the eye (seeded), inside a room for most seeds.
AnalyticScene random_clutter(int seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-20, 20), s(0.05, 3), r(0.02, 0.6);
  AnalyticScene scene;
  if (seed % 3) scene.boxes.push_back(Box3d::cube({0, 0, 0}, 25.0));
  for (int k = 0; k < 5 + seed % 40; ++k) {
    const Vec3d c{u(rng), u(rng), u(rng)};
    if (std::abs(c.x) < 2 && std::abs(c.y) < 2 && std::abs(c.z) < 2) continue;
    scene.boxes.push_back({c, {c.x + s(rng), c.y + s(rng), c.z + s(rng)}});
  }
  for (int k = 0; k < seed % 30; ++k) {
    const double x = u(rng), y = u(rng), z0 = u(rng), z1 = u(rng);
    if (std::abs(x) < 1.5 && std::abs(y) < 1.5) continue;
    scene.cylinders.push_back({x, y, r(rng), std::min(z0, z1), std::max(z0, z1)});
  }
  return scene;
}

TEST(Simplify, RandomClutterKeepsEveryBoundAtLooseAndExactOutlines) {
  // Seeds that once exposed a loose outline tolerance (1.5 px) counting the
  // surface moved over a pixel as a depth error, a tight cap, exact outlines.
  struct Case {
    int seed;
    double boundary_px;
    std::size_t cap;
  };
  for (const Case c : {Case{31, 1.5, 10000}, Case{17, 1.5, 300}, Case{73, 1.5, 10000}, Case{941, 1.5, 300}, Case{12, 0, 10000},
                       Case{9, 0.5, 300}}) {
    const int n = c.seed % 2 ? 128 : 96;
    const auto dense = build_depth_meshes(raycast_analytic_scene(random_clutter(c.seed), {0.1, -0.2, 0.3}, n),
                                          DepthMeshParams{});
    SimplifyParams params;
    params.boundary_error_px = c.boundary_px;
    params.max_triangles = c.cap;
    for (int f = 0; f < kCubeFaces; ++f) {
      const SimplifyResult r = simplify_face_mesh(dense[f], n, params);
      EXPECT_LE(r.achieved.max_depth_error_relative, r.depth_error_bound_used * (1 + 1e-6) + 1e-7)
          << "seed " << c.seed << " face " << f;
      EXPECT_LE(r.depth_error_bound_used, params.depth_error_relative * params.max_depth_error_factor + 1e-12);
      // uv rounding at 96 px (k / 96 is not a float) shows as ~1e-5 px.
      EXPECT_LE(r.achieved.max_boundary_error_px, c.boundary_px + 1e-4) << "seed " << c.seed << " face " << f;
      EXPECT_EQ(r.achieved.flipped_triangles, 0u) << "seed " << c.seed << " face " << f;
      EXPECT_EQ(r.achieved.overlapping_samples, 0u) << "seed " << c.seed << " face " << f;
    }
  }
}

TEST(Simplify, RejectsMeshesThatAreNotPixelGrids) {
  FaceMesh m;
  m.positions = {{1, 0, 0}, {1, 1, 0}, {1, 0, 1}};
  m.uvs = {{0.1f, 0.1f}, {0.5f, 0.1f}, {0.1f, 0.5f}};
  m.indices = {0, 1, 2};
  EXPECT_THROW(simplify_face_mesh(m, 8, SimplifyParams{}), std::invalid_argument);
  m.uvs = {{0, 0}, {0.5f, 0}, {0, 0.5f}};  // on corners, but spanning four pixels
  EXPECT_THROW(simplify_face_mesh(m, 8, SimplifyParams{}), std::invalid_argument);
}

}  // namespace
}  // namespace cellbake
