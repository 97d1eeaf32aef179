// The bake with each sampling backend (issue #12): `--set sample.backend=embree`
// bakes a small store through the CLI, a bad backend name is a clear error,
// and switching between the GL and ray-casting backends recomputes cells
// (their pixels differ within the parity tolerance) while GL backends share hashes.
#include <gtest/gtest.h>

#include "pipeline/bake_config.h"
#include "pipeline/cell_job.h"
#include "pipeline/sample_backend.h"
#include "storage/cell_db.h"
#include "fixture_room_obj.h"
#include "test_support.h"

namespace cellbake {
namespace {

std::string bake_args(const test::TempDir& dir, const std::string& db) {
  return "bake --store " + (dir / "room.store.db").string() +
         " --region 1,1,1.6,7,5,1.6 --cell-size 2 --near-budget 600 --face-size 32 --quiet --out " + (dir / db).string();
}

TEST(BakeBackends, EmbreeBakesEveryCellAndRerunsSkipThem) {
  test::TempDir dir;
  test::ingest_room_store(dir.path());
  const auto first = test::run_cellbake(bake_args(dir, "cells.db") + " --set sample.backend=embree");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("samples rendered by embree on CPU"), std::string::npos) << first.output;
  {
    CellDb db(dir / "cells.db", CellDb::Mode::read_only);
    const auto totals = db.totals();
    EXPECT_EQ(totals.cells_done, 6u);
    EXPECT_EQ(totals.cells_failed, 0u);
    EXPECT_TRUE(db.integrity_ok());
    EXPECT_NE(db.meta("config").value_or("").find("sample.backend=embree"), std::string::npos);
  }
  const auto again = test::run_cellbake(bake_args(dir, "cells.db") + " --set sample.backend=embree");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.output.find("samples rendered by"), std::string::npos) << "nothing was sampled:\n"
                                                                         << again.output;
  const auto before = CellDb(dir / "cells.db", CellDb::Mode::read_only).totals();
  // Switching to OSMesa recomputes (different pixels), with the same number of cells done.
  const auto gl = test::run_cellbake(bake_args(dir, "cells.db") + " --set sample.backend=osmesa");
  ASSERT_EQ(gl.exit_code, 0) << gl.output;
  // The GL renderer string names the rasteriser (llvmpipe here, a GPU's name on one).
  EXPECT_NE(gl.output.find("samples rendered by osmesa on "), std::string::npos) << gl.output;
  const auto after = CellDb(dir / "cells.db", CellDb::Mode::read_only).totals();
  EXPECT_EQ(after.cells_done, 6u);
  EXPECT_NE(before.content_hash, after.content_hash);
}

TEST(BakeBackends, UnknownBackendIsAClearError) {
  test::TempDir dir;
  test::ingest_room_store(dir.path());
  const auto r = test::run_cellbake(bake_args(dir, "cells.db") + " --set sample.backend=vulkan");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("sample.backend"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("embree"), std::string::npos) << r.output;
}

TEST(BakeBackends, HashTellsRayCastingFromRasterisingOnly) {
  BakeConfig c;
  c.regions = {Box3d{{0, 0, 0}, {1, 1, 1}}};
  CellSpec cell;
  cell.bounds = Box3d{{0, 0, 0}, {1, 1, 1}};
  const auto hash = [&](const std::string& backend) {
    c.sample_backend = backend;
    return cell_hashes(cell, c, "store").input;
  };
  EXPECT_EQ(hash("osmesa"), hash("egl"));
  EXPECT_NE(hash("osmesa"), hash("embree"));
  // auto hashes as what it resolves to on this machine (EGL on a GPU, else Embree).
  const std::string resolved = sample_backend_name(resolve_sample_backend(SampleBackend::automatic));
  EXPECT_EQ(hash(resolved), hash("auto"));
  // The cache cap changes no pixel.
  const std::string before = hash("embree");
  c.embree_cache_mb = 64;
  EXPECT_EQ(hash("embree"), before);
  EXPECT_THROW(apply_override(c, "sample.backend=vulkan"), std::runtime_error);
  apply_override(c, "sample.backend=embree");
  EXPECT_EQ(c.sample_backend, "embree");
}

}  // namespace
}  // namespace cellbake
