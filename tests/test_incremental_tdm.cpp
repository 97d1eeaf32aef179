// Incremental textured depth meshes end to end on a small baked room (Wilson
// 2002 ch. 3 and 5): several samples per cell with a dependency tree, delta
// scans that keep only what their ancestors lack, views from the cell corners
// that the root sample alone leaves full of holes, and no seam between the
// near field and the far field along the cull box from anywhere in the cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "stages/encode/encode.h"
#include "storage/cell_db.h"
#include "viewer/decoded_cell.h"
#include "fixture_room_obj.h"
#include "test_support.h"
#include "viewer/view_camera.h"
#include "viewer/view_session.h"

namespace cellbake {
namespace {

// A 12 x 12 x 4 m room with a pillar (x 7..8, y 5..7) and a low wall
// (x 9..9.2, y 2..10, 1 m high) in front of the far wall; one 2 m cell centred
// at (3, 6, 1.6) on a flat region; a cull box small enough that the floor,
// the ceiling and no wall cross it.
struct BakedCell {
  test::TempDir dir;
  std::filesystem::path db;
  explicit BakedCell(const std::string& initial = "corners+centre") {
    BakeConfig c = test::obj_room_bake_config(dir.path(), test::pillar_room_obj(16, {Box3d{{9, 2, 0}, {9.2, 10, 1}}}),
                                              Box3d{{2, 5, 1.6}, {4, 7, 1.6}}, 600, 128);
    c.samples_initial = initial;
    c.far_choice = "tdm";  // incremental depth meshes themselves (exact far geometry would stand in for them)
    EXPECT_EQ(test::bake_quietly(c).cells_baked, 1u);
    db = c.database;
  }
};

BakedCell& cell() {
  static BakedCell baked;
  return baked;
}

ViewRequest request(Vec3d eye, Vec3d look, int max_samples = 0) {
  ViewRequest r;
  r.eye = eye;
  r.look = look;
  r.width = 160;
  r.height = 120;
  r.fov_y_deg = 70;
  r.cell = 1;
  r.max_samples = max_samples;
  r.far_budget = std::uint64_t{1} << 30;
  return r;
}

const std::vector<Vec3d> kCorners = {{2, 5, 1.6}, {4, 5, 1.6}, {2, 7, 1.6}, {4, 7, 1.6}};

TEST(IncrementalTdm, CornersAndCentreFormATreeWhoseDeltaScansAreMostlyRedundant) {
  CellDb db(cell().db, CellDb::Mode::read_only);
  const auto row = db.get_cell(1);
  ASSERT_TRUE(row && row->status == "done") << (row ? row->error : "no cell");
  ASSERT_GE(row->samples.size(), 5u);
  EXPECT_EQ(row->samples[0].eye, (Vec3d{3, 6, 1.6}));
  EXPECT_EQ(row->samples[0].parent, -1);
  std::uint64_t covered = 0, removed = 0;
  for (std::size_t i = 1; i < row->samples.size(); ++i) {
    const SampleRow& s = row->samples[i];
    EXPECT_GE(s.parent, 0);
    EXPECT_LT(s.parent, int(row->samples.size()));
    EXPECT_EQ(s.faces.size(), 6u);
    covered += s.covered_pixels;
    removed += s.removed_pixels;
  }
  EXPECT_GT(double(removed) / double(covered), 0.85) << removed << " of " << covered;
  // The void curve falls as samples are added; the last is below the threshold or the cap was hit.
  EXPECT_GE(row->samples.back().void_after, 0);
}

TEST(IncrementalTdm, CornerViewsHaveFarFewerHolesThanTheRootAlone) {
  ViewSession session(cell().db);
  double root_holes = 0, all_holes = 0;
  for (const Vec3d& eye : kCorners) {
    for (const Vec3d& look : {Vec3d{12, 6, 1.2}, Vec3d{12, 2, 1.0}, Vec3d{12, 10, 1.0}}) {
      const ViewResult all = session.render(request(eye, look), ViewMode::diff, stderr);
      const ViewResult root = session.render(request(eye, look, 1), ViewMode::diff, stderr);
      ASSERT_TRUE(all.metrics && root.metrics);
      EXPECT_LT(all.metrics->hole_fraction, 0.005) << "eye " << eye.x << "," << eye.y << " look " << look.y;
      root_holes += root.metrics->hole_fraction;
      all_holes += all.metrics->hole_fraction;
    }
  }
  EXPECT_GT(root_holes, 0.02);  // the pillar and the low wall hide what the corners see
  EXPECT_LT(all_holes, root_holes / 5) << all_holes << " vs " << root_holes;
}

TEST(IncrementalTdm, NoSeamAlongTheCullBoxFromAnyCorner) {
  CellDb db(cell().db, CellDb::Mode::read_only);
  const auto row = db.get_cell(1);
  ASSERT_TRUE(row);
  const Box3d box = Box3d::cube(row->bounds.center(), row->cull_half_size);
  ASSERT_LT(box.hi.x, 7.0);  // the pillar is outside the box; the floor and ceiling cross it
  ASSERT_LT(box.lo.z, 0.0);
  ViewSession session(cell().db);
  std::size_t band_pixels = 0, band_holes = 0;
  for (const Vec3d& eye : kCorners)
    for (const Vec3d& look : {Vec3d{8, 6, 0.0}, Vec3d{3, 0, 0.3}, Vec3d{3, 12, 0.3}, Vec3d{-2, 6, 3.8}}) {
      const ViewRequest r = request(eye, look);
      const ViewResult v = session.render(r, ViewMode::diff, stderr);
      ASSERT_TRUE(v.truth && v.impostor);
      const RenderCamera cam = look_at_camera(r.eye, r.look, {0, 0, 1}, r.fov_y_deg, r.width, r.height, r.near_plane);
      for (int j = 0; j < r.height; ++j)
        for (int i = 0; i < r.width; ++i) {
          const std::size_t k = std::size_t(j) * r.width + i;
          if (!v.truth->covered(k)) continue;
          const double s = cam.tan_left + (i + 0.5) / r.width * (cam.tan_right - cam.tan_left);
          const double t = cam.tan_top - (j + 0.5) / r.height * (cam.tan_top - cam.tan_bottom);
          const Vec3d p = cam.eye + (cam.forward + cam.right * s + cam.up * t) * double(v.truth->depth[k]);
          // Within 10 cm of the box's boundary (inside or outside), on a surface the box cuts.
          double outside = 0, inside = 1e9;
          for (int a = 0; a < 3; ++a) {
            outside = std::max({outside, box.lo[a] - p[a], p[a] - box.hi[a]});
            inside = std::min({inside, p[a] - box.lo[a], box.hi[a] - p[a]});
          }
          if (outside > 0.1 || (outside == 0 && inside > 0.1)) continue;
          ++band_pixels;
          if (!v.impostor->covered(k)) {
            ++band_holes;
            ADD_FAILURE() << "hole at pixel " << i << "," << j << " from " << eye.x << "," << eye.y << " looking at "
                          << look.x << "," << look.y << "," << look.z << ": world " << p.x << "," << p.y << "," << p.z;
          }
        }
    }
  EXPECT_GT(band_pixels, 500u);
  EXPECT_EQ(band_holes, 0u) << "of " << band_pixels << " pixels along the cull box";
}

TEST(IncrementalTdm, FaceTilesHoldEveryTriangleOnceInsideTheirBounds) {
  CellDb db(cell().db, CellDb::Mode::read_only);
  const auto row = db.get_cell(1);
  ASSERT_TRUE(row);
  const DecodedCell decoded = decode_cell(*row);
  std::size_t faces = 0;
  for (const DecodedFace& f : decoded.faces) {
    // The same triangles as the stored mesh, reordered tile by tile.
    const FaceMesh stored = decode_face_mesh(row->samples[std::size_t(f.sample)].faces[std::size_t(f.face)].mesh);
    auto triangles = [](const FaceMesh& m) {
      std::vector<std::array<std::uint32_t, 3>> t;
      for (std::size_t i = 0; i < m.indices.size(); i += 3) t.push_back({m.indices[i], m.indices[i + 1], m.indices[i + 2]});
      std::sort(t.begin(), t.end());
      return t;
    };
    EXPECT_EQ(triangles(f.mesh), triangles(stored));
    std::uint32_t next = 0;
    for (const FaceTile& t : f.tiles) {
      EXPECT_EQ(t.first_index, next);
      EXPECT_GT(t.index_count, 0u);
      next += t.index_count;
      for (std::uint32_t i = t.first_index; i < t.first_index + t.index_count; ++i) {
        const Vec3f& p = f.mesh.positions[f.mesh.indices[i]];
        const Vec3d w = f.eye + Vec3d{p.x, p.y, p.z};
        EXPECT_TRUE(t.bounds.contains(Box3d{w, w}));
      }
    }
    EXPECT_EQ(next, f.mesh.indices.size());
    faces += f.tiles.size() > 1;
  }
  EXPECT_GT(faces, 0u);  // some face spans several tiles
}

TEST(IncrementalTdm, CentreOnlyBakesOneSampleAndMaxSamplesOneDrawsIt) {
  BakedCell centre("centre");
  CellDb db(centre.db, CellDb::Mode::read_only);
  const auto row = db.get_cell(1);
  ASSERT_TRUE(row);
  // The best-next-view search may add samples beyond the initial one.
  ASSERT_GE(row->samples.size(), 1u);
  EXPECT_EQ(row->samples[0].eye, (Vec3d{3, 6, 1.6}));
  ViewSession session(centre.db);
  const ViewResult one = session.render(request({3, 6, 1.6}, {12, 6, 1.2}, 1), ViewMode::diff, stderr);
  ASSERT_TRUE(one.metrics);
  EXPECT_EQ(one.impostor_stats.samples_drawn, 1u);
  EXPECT_LT(one.metrics->hole_fraction, 0.01);
}

}  // namespace
}  // namespace cellbake
