// The bake end to end on small synthetic stores: resumability (skip, selective
// recompute, kill -9 and resume), failure isolation, determinism across thread
// counts, and the database's one-transaction-per-cell integrity.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <thread>
#include <sstream>

#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "stages/simplify/simplify.h"
#include "storage/cell_db.h"
#include "fixture_room_obj.h"
#include "test_support.h"

namespace cellbake {
namespace {

// The room of fixture_room_obj.h, ingested in 128-triangle chunks.
std::filesystem::path make_room_store(const test::TempDir& dir) {
  return test::ingest_room_store(dir.path());
}

BakeConfig room_config(const test::TempDir& dir, const std::string& db) {
  BakeConfig c;
  c.store = dir / "room.store.db";
  c.regions = {Box3d{{1, 1, 1.6}, {11, 7, 1.6}}};  // 5 x 3 cells of 2 m
  c.cell_size = 2.0;
  c.near_budget = 600;
  c.face_size = 32;
  c.image_format = "png";
  c.database = dir / db;
  return c;
}

BakeOptions quiet(int threads = 2) {
  BakeOptions o;
  o.threads = threads;
  o.quiet = true;
  return o;
}

TEST(Bake, BakesEveryCellAndSkipsThemOnRerun) {
  test::TempDir dir;
  make_room_store(dir);
  BakeConfig c = room_config(dir, "cells.db");
  BakeSummary s = run_bake(c, quiet());
  EXPECT_EQ(s.cells_selected, 15u);
  EXPECT_EQ(s.cells_baked, 15u);
  EXPECT_EQ(s.cells_failed, 0u);

  CellDb db(c.database, CellDb::Mode::read_only);
  EXPECT_TRUE(db.integrity_ok());
  auto cell = db.get_cell(1);
  ASSERT_TRUE(cell);
  EXPECT_EQ(cell->status, "done");
  EXPECT_GE(cell->cull_half_size, 1.0);
  EXPECT_LE(cell->near_triangles, 600u);
  // Corners + centre of the flat cell, maybe more by best-next-view.
  ASSERT_GE(cell->samples.size(), 5u);
  ASSERT_LE(cell->samples.size(), std::size_t(c.samples_max));
  for (const SampleRow& sample : cell->samples) ASSERT_EQ(sample.faces.size(), 6u);
  EXPECT_EQ(cell->samples[0].parent, -1);
  EXPECT_GT(cell->far_triangles + cell->far_geometry_triangles, 0u);  // a far field, of depth meshes or geometry
  for (const char* stage : {"cull_box", "sample", "void", "depth_mesh", "redundancy", "simplify", "encode"})
    EXPECT_TRUE(cell->stage_seconds.count(stage)) << stage;

  s = run_bake(c, quiet());
  EXPECT_EQ(s.cells_up_to_date, 15u);
  EXPECT_EQ(s.cells_baked, 0u);
}

TEST(Bake, FacesStoreTheErrorMeasuredOnTheirSimplifiedMesh) {
  test::TempDir dir;
  make_room_store(dir);
  BakeConfig c = room_config(dir, "cells.db");
  c.far_choice = "tdm";  // every face keeps its mesh (the room's cheapest far field is all geometry)
  c.samples_max = 2;
  run_bake(c, quiet());
  CellDb db(c.database, CellDb::Mode::read_only);
  const double depth_bound = c.depth_error_relative * SimplifyParams{}.max_depth_error_factor * (1 + 1e-6) + 1e-7;
  const double boundary_bound = std::max(c.boundary_error_px, c.delta_boundary_error_px) + 1e-9;
  int measured = 0, meshes = 0;
  ASSERT_EQ(db.cell_ids().size(), 15u);
  for (const std::int64_t id : db.cell_ids()) {
    const auto cell = db.get_cell(id);
    ASSERT_TRUE(cell) << id;
    double max_boundary = 0, max_depth = 0;
    for (const SampleRow& sample : cell->samples)
      for (const FaceRow& f : sample.faces) {
        EXPECT_GE(f.depth_error, 0);
        EXPECT_GE(f.boundary_error_px, 0);
        EXPECT_LE(f.depth_error, depth_bound) << "cell " << id << " face " << f.face;
        EXPECT_LE(f.boundary_error_px, boundary_bound) << "cell " << id << " face " << f.face;
        if (f.triangles == 0) {  // nothing kept: nothing measured
          EXPECT_EQ(f.depth_error, 0);
          EXPECT_EQ(f.boundary_error_px, 0);
        }
        meshes += f.triangles > 0;
        measured += f.depth_error > 0 || f.boundary_error_px > 0;
        max_boundary = std::max(max_boundary, f.boundary_error_px);
        max_depth = std::max(max_depth, f.depth_error);
      }
    EXPECT_EQ(cell->max_boundary_error_px, max_boundary) << id;
    EXPECT_EQ(cell->max_depth_error, max_depth) << id;
  }
  EXPECT_GT(meshes, 0);
  EXPECT_GT(measured, 0);  // the simplifier's errors were measured, not left at zero
}

TEST(Bake, ChangedParametersRecomputeOnlyWhatTheyAffect) {
  test::TempDir dir;
  make_room_store(dir);
  BakeConfig c = room_config(dir, "cells.db");
  c.far_choice = "tdm";  // faces keep their images (the room's cheapest far field is all geometry)
  run_bake(c, quiet());
  const std::string before = CellDb(c.database, CellDb::Mode::read_only).totals().content_hash;

  // An encoding parameter: every cell re-encoded, cull boxes reused.
  c.image_format = "jpeg";
  BakeSummary s = run_bake(c, quiet());
  EXPECT_EQ(s.cells_baked, 15u);
  EXPECT_EQ(s.cull_reused, 15u);
  EXPECT_NE(CellDb(c.database, CellDb::Mode::read_only).totals().content_hash, before);

  // Back to the original: the same content as the first bake.
  c.image_format = "png";
  run_bake(c, quiet());
  EXPECT_EQ(CellDb(c.database, CellDb::Mode::read_only).totals().content_hash, before);

  // Only the sample placement: every cell re-sampled, cull boxes kept.
  c.samples_initial = "centre";
  s = run_bake(c, quiet());
  EXPECT_EQ(s.cells_baked, 15u);
  EXPECT_EQ(s.cull_reused, 15u);
  c.samples_initial = "corners+centre";
  run_bake(c, quiet());
  EXPECT_EQ(CellDb(c.database, CellDb::Mode::read_only).totals().content_hash, before);

  // A larger region: only the new cells are baked.
  c.regions = {Box3d{{1, 1, 1.6}, {11, 9, 1.6}}};  // 5 x 4 cells: 5 new
  s = run_bake(c, quiet());
  EXPECT_EQ(s.cells_up_to_date, 15u);
  EXPECT_EQ(s.cells_baked, 5u);

  // A cell selection with --force recomputes just those.
  BakeOptions o = quiet();
  o.cells = "2-3";
  o.force = true;
  s = run_bake(c, o);
  EXPECT_EQ(s.cells_selected, 2u);
  EXPECT_EQ(s.cells_baked, 2u);
}

TEST(Bake, SameContentWhateverTheThreadCount) {
  test::TempDir dir;
  make_room_store(dir);
  BakeConfig a = room_config(dir, "one.db"), b = room_config(dir, "two.db");
  run_bake(a, quiet(1));
  run_bake(b, quiet(2));
  const auto ta = CellDb(a.database, CellDb::Mode::read_only).totals();
  const auto tb = CellDb(b.database, CellDb::Mode::read_only).totals();
  EXPECT_EQ(ta.cells_done, 15u);
  EXPECT_EQ(ta.content_hash, tb.content_hash);
}

TEST(Bake, AFailingCellIsRecordedAndTheOthersFinish) {
  test::TempDir dir;
  // Compact clusters 10 m apart along x, one chunk each; cells sit on clusters.
  std::ostringstream o;
  int next = 1;
  for (int k = 0; k < 6; ++k) test::obj_box(o, next, {10.0 * k - 0.4, -0.4, -0.4}, {10.0 * k + 0.4, 0.4, 0.4}, 3);
  test::write_text(dir / "clusters.obj", o.str());
  IngestParams p;
  p.max_chunk_triangles = 128;
  ingest_models({dir / "clusters.obj"}, dir / "s.db", p, tbb_parallel_for());
  // Corrupt the chunk of the cluster at x = 30 (chunks are numbered in kd order; find it by bounds).
  const std::string sql = "UPDATE chunks SET geometry = x'0011' WHERE min_x > 25 AND max_x < 35";
  ASSERT_EQ(std::system(("sqlite3 " + (dir / "s.db").string() + " \"" + sql + "\"").c_str()), 0);

  BakeConfig c;
  c.store = dir / "s.db";
  c.cell_size = 10;
  c.near_budget = 120;
  c.face_size = 16;
  c.database = dir / "cells.db";
  // Cell size 10 puts a cell on every cluster; only the cell whose cull box holds the
  // corrupt chunk whole never reads it.
  c.regions = {Box3d{{-5, -5, -5}, {55, 5, 5}}};
  // The rasteriser loads only the chunks a face sees; the Embree backend loads
  // whole groups of chunks (up to 1 M triangles each), so there one corrupt
  // chunk fails every cell whose far field reaches its group. The pipeline's
  // promise (a failed row per cell, the others finish) is what is tested here.
  c.sample_backend = "osmesa";
  BakeSummary s = run_bake(c, quiet());
  EXPECT_EQ(s.cells_selected, 6u);
  EXPECT_GE(s.cells_failed, 1u);
  EXPECT_GE(s.cells_baked, 1u);
  CellDb db(c.database, CellDb::Mode::read_only);
  bool named = false;
  for (const auto& id : db.cell_ids()) {
    auto cell = db.get_cell(id, false);
    if (cell->status == "failed") {
      named |= cell->error.find("cell " + std::to_string(id)) != std::string::npos &&
               cell->error.find("stage ") != std::string::npos && cell->error.find("chunk") != std::string::npos;
    }
  }
  EXPECT_TRUE(named);
  EXPECT_TRUE(db.integrity_ok());
}

TEST(Bake, KilledBakeResumesToTheSameDatabase) {
  test::TempDir dir;
  make_room_store(dir);
  const std::string common = "bake --store " + (dir / "room.store.db").string() +
                             " --region 1,1,1.6,11,11,1.6 --cell-size 1 --near-budget 600 --face-size 64 --quiet";
  // Reference: an uninterrupted bake (100 cells).
  auto ref = test::run_cellbake(common + " --out " + (dir / "ref.db").string());
  ASSERT_EQ(ref.exit_code, 0) << ref.output;
  // Kill -9 once a few cells are committed (polling the database as a reader), then rerun.
  const std::string db = (dir / "killed.db").string();
  const std::string cmd = "exec " + std::string(CELLBAKE_BINARY) + " " + common + " --out " + db + " >/dev/null 2>&1";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  std::uint64_t done_before_kill = 0;
  for (int i = 0; i < 1200 && done_before_kill < 5; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    try {
      done_before_kill = CellDb(db, CellDb::Mode::read_only).totals().cells_done;
    } catch (const std::exception&) {
      // not created yet
    }
  }
  kill(pid, SIGKILL);
  int wait_status = 0;
  waitpid(pid, &wait_status, 0);
  EXPECT_GE(done_before_kill, 5u);
  {
    CellDb partial(db, CellDb::Mode::read_only);
    EXPECT_TRUE(partial.integrity_ok());
    EXPECT_LT(partial.totals().cells_done, 100u);  // it really was interrupted
  }
  auto resumed = test::run_cellbake(common + " --out " + db);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  CellDb a(dir / "ref.db", CellDb::Mode::read_only), b(db, CellDb::Mode::read_only);
  EXPECT_TRUE(b.integrity_ok());
  EXPECT_EQ(a.totals().cells_done, 100u);
  EXPECT_EQ(a.totals().content_hash, b.totals().content_hash);
  auto status = test::run_cellbake("status " + db + " --json");
  EXPECT_NE(status.output.find("\"cells_pending\": 0"), std::string::npos) << status.output;
}

}  // namespace
}  // namespace cellbake

namespace cellbake {
namespace {

TEST(BakeCli, ThreadCountsOutOfRangeAreRefusedNamingTheOption) {
  test::TempDir dir;
  make_room_store(dir);
  const std::string store = (dir / "room.store.db").string();
  for (const char* threads : {"1073741824", "-1"}) {
    const auto bake = test::run_cellbake("bake --store '" + store + "' --up z --region 1,1,1.6,3,3,1.6 --cell-size 2 --threads " +
                                         threads + " --out '" + (dir / "cells.db").string() + "'");
    EXPECT_NE(bake.exit_code, 0) << bake.output;
    EXPECT_NE(bake.output.find("--threads"), std::string::npos) << bake.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "cells.db"));
    const auto verify = test::run_cellbake("verify '" + (dir / "none.db").string() + "' --report '" +
                                           (dir / "report").string() + "' --threads " + threads);
    EXPECT_NE(verify.exit_code, 0) << verify.output;
    EXPECT_NE(verify.output.find("--threads"), std::string::npos) << verify.output;
  }
}

}  // namespace
}  // namespace cellbake
