// Dense depth meshes from analytic cube-map samples (no GL): flat box faces,
// bit-identical shared cube edges, skins at silhouettes, background, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <tuple>

#include "pipeline/scenes/depth_mesh_analytic_scene.h"
#include "stages/depth_mesh.h"

namespace cellbake {
namespace {

using PositionKey = std::tuple<float, float, float>;
PositionKey key(Vec3f p) { return {p.x, p.y, p.z}; }

bool on_border(Uv uv) { return uv.u == 0.0f || uv.v == 0.0f || uv.u == 1.0f || uv.v == 1.0f; }

std::set<PositionKey> border_positions(const FaceMesh& m) {
  std::set<PositionKey> out;
  for (std::size_t v = 0; v < m.positions.size(); ++v)
    if (on_border(m.uvs[v])) out.insert(key(m.positions[v]));
  return out;
}

double distance(Vec3f p) { return std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z); }

TEST(DepthMesh, BoxSeenFromItsCentreGivesFlatFacesThatMeetBitIdentically) {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 1.0));
  const int n = 24;
  const CubeSample sample = raycast_analytic_scene(scene, {0, 0, 0}, n);
  DepthMeshStats stats;
  const auto meshes = build_depth_meshes(sample, DepthMeshParams{}, &stats);
  EXPECT_EQ(stats.background_pixels, 0u);
  EXPECT_EQ(stats.skin_edges, 0u);
  EXPECT_EQ(stats.triangles, std::size_t(6 * 2 * n * n));
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceMesh& m = meshes[f];
    ASSERT_EQ(m.triangle_count(), std::size_t(2 * n * n));
    EXPECT_EQ(m.positions.size(), std::size_t((n + 1) * (n + 1)));  // one vertex per pixel corner
    const FaceBasis b = cube_face_basis(f);
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
      const Vec3f p = m.positions[v];
      // Exactly on the wall: forward component 1, and on the ray through the uv corner.
      EXPECT_EQ(double(p.x) * b.forward.x + double(p.y) * b.forward.y + double(p.z) * b.forward.z, 1.0);
      const double s = double(p.x) * b.right.x + double(p.y) * b.right.y + double(p.z) * b.right.z;
      const double t = double(p.x) * b.up.x + double(p.y) * b.up.y + double(p.z) * b.up.z;
      EXPECT_NEAR(s, 2.0 * m.uvs[v].u - 1.0, 1e-6);
      EXPECT_NEAR(t, 1.0 - 2.0 * m.uvs[v].v, 1e-6);
    }
  }
  // Every pair of adjacent faces shares exactly n + 1 border positions, bit for bit.
  int adjacent_pairs = 0;
  for (int a = 0; a < kCubeFaces; ++a)
    for (int b = a + 1; b < kCubeFaces; ++b) {
      const auto pa = border_positions(meshes[a]), pb = border_positions(meshes[b]);
      std::vector<PositionKey> common;
      std::set_intersection(pa.begin(), pa.end(), pb.begin(), pb.end(), std::back_inserter(common));
      if (a / 2 == b / 2) {
        EXPECT_TRUE(common.empty()) << "opposite faces " << a << ", " << b;
      } else {
        ++adjacent_pairs;
        EXPECT_EQ(common.size(), std::size_t(n + 1)) << "faces " << a << ", " << b;
      }
    }
  EXPECT_EQ(adjacent_pairs, 12);
}

TEST(DepthMesh, TrianglesAreCounterClockwiseSeenFromTheEye) {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 1.0));
  const auto meshes = build_depth_meshes(raycast_analytic_scene(scene, {0.1, -0.2, 0.3}, 16), DepthMeshParams{});
  for (const FaceMesh& m : meshes)
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const Vec3f a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
                  c = m.positions[m.indices[3 * t + 2]];
      const Vec3d da{a.x, a.y, a.z}, db{b.x, b.y, b.z}, dc{c.x, c.y, c.z};
      // Normal faces the eye (at the origin): (b - a) x (c - a) points against a.
      EXPECT_LT(dot(cross(db - da, dc - da), da), 0.0);
    }
}

TEST(DepthMesh, ThinPipeInFrontOfAWallLeavesNoSkinTriangles) {
  AnalyticScene scene;
  scene.boxes.push_back({{5, -50, -50}, {6, 50, 50}});                  // wall at x = 5
  scene.cylinders.push_back({2.5, 0.0, 0.05, -10, 10});                 // pipe ~2.5 px wide at 128^2
  const int n = 128;
  DepthMeshParams params;
  DepthMeshStats stats;
  const auto meshes = build_depth_meshes(raycast_analytic_scene(scene, {0, 0, 0}, n), params, &stats);
  const FaceMesh& m = meshes[0];  // +X
  EXPECT_GT(stats.skin_edges, std::size_t(2 * n));  // both silhouettes of the pipe, all rows
  std::size_t pipe_triangles = 0, wall_triangles = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    double lo = 1e300, hi = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = distance(m.positions[m.indices[3 * t + k]]);
      lo = std::min(lo, d), hi = std::max(hi, d);
    }
    EXPECT_LE(hi - lo, params.max_relative_depth_jump * lo) << "triangle " << t << " spans a skin";
    pipe_triangles += hi < 3.0;
    wall_triangles += lo > 4.9;
  }
  EXPECT_GT(pipe_triangles, std::size_t(2 * n));
  EXPECT_GT(wall_triangles, std::size_t(n * n));
}

// The thesis' multi-source test (§3.4.2.1.1): a pipe 0.3 m in front of a
// wall 6 m away differs from it by 5 % in depth and meets it at ~13 degrees
// to the ray, so the single-source tests join them into a slanted sheet; a
// second sample 3 m to the side sees the wall past the sheet's midpoints
// (3.4 px of parallax at 256^2), which makes those edges skins. The same
// witness cuts nothing on a floor seen out to grazing angles (a surface
// through a midpoint is never seen past). (At a concave corner the chord
// between the two surfaces' pixels does cross empty space, and a witness may
// cut it; each side's corner vertices are then interpolated from its own
// pixels, so the two meshes overlap there rather than part.)
TEST(DepthMesh, AWitnessSeeingPastAMidpointMakesItASkin) {
  AnalyticScene scene;
  scene.boxes.push_back({{6, -60, -60}, {7, 60, 60}});   // wall at x = 6
  scene.cylinders.push_back({5.8, 0.0, 0.1, -2, 2});     // pipe ~9 px wide at 256^2
  const int n = 256;
  const CubeSample centre = raycast_analytic_scene(scene, {0, 0, 0}, n);
  const CubeSample side = raycast_analytic_scene(scene, {0, 3, 0}, n);
  std::array<std::vector<float>, kCubeFaces> side_depth;
  for (int f = 0; f < kCubeFaces; ++f) side_depth[std::size_t(f)] = side.faces[std::size_t(f)].depth;

  DepthMeshParams alone;
  DepthMeshParams witnessed;
  witnessed.witnesses.push_back({side.eye, &side_depth, n});
  DepthMeshStats alone_stats, witnessed_stats;
  const auto sheet = build_depth_meshes(centre, alone, &alone_stats);
  const auto cut = build_depth_meshes(centre, witnessed, &witnessed_stats);
  // The silhouette facing the witness, on each of the ~170 rows the pipe covers.
  EXPECT_GE(witnessed_stats.skin_edges, alone_stats.skin_edges + 150);
  // Triangles spanning the gap (more than 1.5 % in depth): the sheets from
  // pipe to wall. The witness cuts the one on the pipe's side facing it; it
  // cannot see past the far side or the pipe's open ends from where it is.
  const auto sheet_triangles = [](const FaceMesh& m) {
    std::size_t spanning = 0;
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      double lo = 1e300, hi = 0;
      for (int k = 0; k < 3; ++k) {
        const double d = distance(m.positions[m.indices[3 * t + k]]);
        lo = std::min(lo, d), hi = std::max(hi, d);
      }
      spanning += hi - lo > 0.015 * lo;
    }
    return spanning;
  };
  const std::size_t before = sheet_triangles(sheet[0]), after = sheet_triangles(cut[0]);
  EXPECT_GT(before, std::size_t(2 * 150));
  EXPECT_LT(after * 10, before * 6) << before << " -> " << after;  // the side facing the witness is gone
  // No pipe: the witness sees the floor where the centre does.
  AnalyticScene room;
  room.boxes.push_back({{-60, -60, -3}, {60, 60, -2}});
  const CubeSample room_centre = raycast_analytic_scene(room, {0, 0, 0}, n);
  const CubeSample room_side = raycast_analytic_scene(room, {0, 3, 0}, n);
  for (int f = 0; f < kCubeFaces; ++f) side_depth[std::size_t(f)] = room_side.faces[std::size_t(f)].depth;
  witnessed.witnesses[0].eye = room_side.eye;
  DepthMeshStats room_alone, room_witnessed;
  build_depth_meshes(room_centre, alone, &room_alone);
  build_depth_meshes(room_centre, witnessed, &room_witnessed);
  EXPECT_EQ(room_witnessed.skin_edges, room_alone.skin_edges);
}

TEST(DepthMesh, SurfaceNearlyParallelToTheRayIsASkin) {
  // A floor seen at grazing angles near the horizon: the angle test, not the
  // depth jump test, must cut it (jump test disabled here).
  AnalyticScene scene;
  scene.boxes.push_back({{-1000, -1000, -2}, {1000, 1000, -1}});
  DepthMeshParams params;
  params.max_relative_depth_jump = 1e9;
  DepthMeshStats with_angle, without_angle;
  build_depth_meshes(raycast_analytic_scene(scene, {0, 0, 0}, 32), params, &with_angle);
  params.skin_angle_degrees = 0;
  build_depth_meshes(raycast_analytic_scene(scene, {0, 0, 0}, 32), params, &without_angle);
  EXPECT_GT(with_angle.skin_edges, without_angle.skin_edges);
}

TEST(DepthMesh, BackgroundPixelsProduceNoTriangles) {
  AnalyticScene scene;
  scene.boxes.push_back({{3, -0.5, -0.5}, {4, 0.5, 0.5}});  // small box ahead on +X only
  const int n = 32;
  const CubeSample sample = raycast_analytic_scene(scene, {0, 0, 0}, n);
  std::size_t covered = 0;
  for (float z : sample.faces[0].depth) covered += std::isfinite(z);
  ASSERT_GT(covered, 0u);
  DepthMeshStats stats;
  const auto meshes = build_depth_meshes(sample, DepthMeshParams{}, &stats);
  EXPECT_EQ(meshes[0].triangle_count(), 2 * covered);
  for (int f = 1; f < kCubeFaces; ++f) {
    EXPECT_EQ(meshes[f].triangle_count(), 0u);
    EXPECT_TRUE(meshes[f].positions.empty());
  }
  EXPECT_EQ(stats.background_pixels, std::size_t(6 * n * n) - covered);
  EXPECT_EQ(stats.triangles, 2 * covered);
}

TEST(DepthMesh, IsDeterministic) {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 5.0));
  scene.boxes.push_back({{1, 1, -1}, {2, 3, 1}});
  scene.cylinders.push_back({-1.5, 0.5, 0.3, -4, 2});
  const CubeSample sample = raycast_analytic_scene(scene, {0.2, 0.1, 0.3}, 40);
  const auto a = build_depth_meshes(sample, DepthMeshParams{});
  const auto b = build_depth_meshes(sample, DepthMeshParams{});
  for (int f = 0; f < kCubeFaces; ++f) {
    EXPECT_EQ(a[f].positions, b[f].positions);
    EXPECT_EQ(a[f].uvs, b[f].uvs);
    EXPECT_EQ(a[f].indices, b[f].indices);
  }
}

TEST(DepthMesh, OneFaceAloneIsBitIdenticalToThatFaceOfTheWholeCube) {
  // Faces meshed one at a time, in any order (a far choice meshes only the
  // faces it needs), give the same bits, border corners included.
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 5.0));
  scene.boxes.push_back({{1, 1, -1}, {2, 3, 1}});
  scene.boxes.push_back({{-3, -2, 2}, {-1, 4, 4.5}});  // across an upper cube edge
  scene.cylinders.push_back({-1.5, 0.5, 0.3, -4, 2});
  const CubeSample sample = raycast_analytic_scene(scene, {0.2, 0.1, 0.3}, 40);
  const auto all = build_depth_meshes(sample, DepthMeshParams{});
  for (int f : {5, 2, 0, 4, 1, 3}) {
    const FaceMesh one = build_depth_mesh_face(sample, DepthMeshParams{}, f);
    EXPECT_GT(one.triangle_count(), 0u) << f;
    EXPECT_EQ(one.positions, all[f].positions) << f;
    EXPECT_EQ(one.uvs, all[f].uvs) << f;
    EXPECT_EQ(one.indices, all[f].indices) << f;
  }
  // One scratch carried across faces, samples of another size and back: the
  // same bits as fresh memory (nothing left from an earlier call shows).
  DepthMeshScratch scratch;
  const CubeSample other = raycast_analytic_scene(scene, {-0.4, 0.3, -0.2}, 24);
  const auto other_all = build_depth_meshes(other, DepthMeshParams{});
  for (int round = 0; round < 2; ++round)
    for (int f : {3, 0, 5, 1, 4, 2}) {
      const FaceMesh one = build_depth_mesh_face(sample, DepthMeshParams{}, f, &scratch);
      EXPECT_EQ(one.positions, all[f].positions) << f;
      EXPECT_EQ(one.indices, all[f].indices) << f;
      const FaceMesh small = build_depth_mesh_face(other, DepthMeshParams{}, (f + round) % kCubeFaces, &scratch);
      EXPECT_EQ(small.positions, other_all[(f + round) % kCubeFaces].positions) << f;
      EXPECT_EQ(small.indices, other_all[(f + round) % kCubeFaces].indices) << f;
    }
  EXPECT_THROW(build_depth_mesh_face(sample, DepthMeshParams{}, 6), std::invalid_argument);
  CubeSample bad_depth = sample;
  bad_depth.faces[2].depth[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(build_depth_mesh_face(bad_depth, DepthMeshParams{}, 0), std::invalid_argument);
}

TEST(DepthMesh, RejectsInconsistentInput) {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 1.0));
  CubeSample sample = raycast_analytic_scene(scene, {0, 0, 0}, 8);
  CubeSample bad_size = sample;
  bad_size.faces[3].size = 4;
  EXPECT_THROW(build_depth_meshes(bad_size, DepthMeshParams{}), std::invalid_argument);
  CubeSample bad_depth = sample;
  bad_depth.faces[2].depth[5] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(build_depth_meshes(bad_depth, DepthMeshParams{}), std::invalid_argument);
  bad_depth.faces[2].depth[5] = -1.0f;
  EXPECT_THROW(build_depth_meshes(bad_depth, DepthMeshParams{}), std::invalid_argument);
}

}  // namespace
}  // namespace cellbake
