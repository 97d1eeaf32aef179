// A geometry store is verified before it is trusted (issue #41, item 2):
// `status STORE --check` recomputes its content hash, checks the R-tree
// against the chunk rows and decodes every chunk blob, naming each problem
// with its chunk; `bake` and `verify` refuse a store whose row counts differ
// from what ingest recorded (the full check with --check-store); a store
// written before the counts were recorded is still accepted.
#include <gtest/gtest.h>

#include <functional>
#include <sstream>
#include <string>

#include "pipeline/ingest.h"
#include "storage/geometry_store.h"
#include "storage/sqlite_db.h"
#include "storage/store_check.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

// A 4 x 4 x 3 m box room of 1 200 triangles in chunks of at most 64: a
// store with a few dozen chunk rows, ingested in a moment.
class StoreCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    std::ostringstream o;
    int next = 1;
    test::obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 10);
    test::write_text(dir_ / "box.obj", o.str());
    IngestParams params;
    params.max_chunk_triangles = 64;
    ingest_models({dir_ / "box.obj"}, dir_ / "s.db", params,
                  [](std::size_t n, const std::function<void(std::size_t)>& fn) {
                    for (std::size_t i = 0; i < n; ++i) fn(i);
                  });
  }
  std::string store() const { return (dir_ / "s.db").string(); }
  void sql(const std::string& statement) const {
    SqliteDb d(store(), SqliteDb::Mode::read_write_create);
    d.exec(statement);
  }
  test::CommandResult bake(const std::string& extra = "") const {
    return test::run_cellbake("bake --store " + store() + " --region=0.5,0.5,1,3.5,3.5,1 --cell-size 1.5 " +
                              "--face-size 16 --quiet --threads 1 --cells 1 --out " +
                              (dir_ / "cells.db").string() + " " + extra);
  }
  test::TempDir dir_;
};

TEST_F(StoreCheck, AFreshStorePassesAndRecordsItsRowCounts) {
  EXPECT_TRUE(check_store(store()).empty());
  EXPECT_TRUE(check_store_rows(store()).empty());
  SqliteDb d(store(), SqliteDb::Mode::read_only);
  SqliteStatement s(d, "SELECT value FROM meta WHERE key = 'rows'");
  ASSERT_TRUE(s.step());
  EXPECT_EQ(s.column_text(0).rfind("chunks=", 0), 0u) << s.column_text(0);
  const auto r = test::run_cellbake("status " + store() + " --check");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("check: sound"), std::string::npos) << r.output;
  EXPECT_EQ(bake("--check-store").exit_code, 0);
}

TEST_F(StoreCheck, DeletedChunkRowsAreFoundAndRefusedByBake) {
  GeometryStore before(store());
  ASSERT_GE(before.summary().chunks, 4u);
  sql("DELETE FROM chunks WHERE id IN (2, 3)");
  const auto problems = check_store(store());
  std::string all;
  for (const auto& p : problems) all += describe(p) + "\n";
  EXPECT_NE(all.find("table chunks has"), std::string::npos) << all;
  EXPECT_NE(all.find("chunk 2: an R-tree entry names a chunk the store does not hold"), std::string::npos)
      << all;
  EXPECT_NE(all.find("content hash mismatch"), std::string::npos) << all;

  const auto status = test::run_cellbake("status " + store() + " --check");
  EXPECT_NE(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("chunk 3: an R-tree entry names a chunk"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("1 damaged geometry store"), std::string::npos) << status.output;

  const auto b = bake();  // the cheap check: row counts
  EXPECT_NE(b.exit_code, 0) << b.output;
  EXPECT_NE(b.output.find("geometry store does not match what ingest wrote"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("table chunks has"), std::string::npos) << b.output;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cells.db"));
}

TEST_F(StoreCheck, DeletedOrMovedRTreeEntriesAreNamedByChunk) {
  sql("DELETE FROM chunk_rtree WHERE id = 1");
  sql("UPDATE chunk_rtree SET min_x = min_x + 1, max_x = max_x + 1 WHERE id = 2");
  const auto status = test::run_cellbake("status " + store() + " --check --json");
  EXPECT_NE(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("no R-tree entry"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("does not match its bounds"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("\"chunk\": 2"), std::string::npos) << status.output;
  const auto b = bake();
  EXPECT_NE(b.exit_code, 0) << b.output;
  EXPECT_NE(b.output.find("table chunk_rtree has"), std::string::npos) << b.output;
}

TEST_F(StoreCheck, ACorruptChunkBlobIsFoundByTheFullCheckAndBakeCheckStore) {
  // Same row counts: only the full check (blob decode, content hash) sees it.
  sql("UPDATE chunks SET geometry = substr(geometry, 1, 40) WHERE id = 3");
  const auto status = test::run_cellbake("status " + store() + " --check");
  EXPECT_NE(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("chunk 3: chunk blob"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("content hash mismatch"), std::string::npos) << status.output;
  const auto b = bake("--check-store");
  EXPECT_NE(b.exit_code, 0) << b.output;
  EXPECT_NE(b.output.find("chunk 3: chunk blob"), std::string::npos) << b.output;
}

// The far field's chunk levels (issue #35): stored at ingest, part of the
// content hash, checked and loaded by level.
TEST(StoreLevels, IngestStoresLevelsInTheHashAndTheCheckFindsADamagedOne) {
  test::TempDir dir;
  std::ostringstream o;
  int next = 1;
  test::obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 10);  // one chunk of 1 200 triangles
  test::write_text(dir / "box.obj", o.str());
  const auto serial = [](std::size_t n, const std::function<void(std::size_t)>& fn) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
  };
  IngestParams params;
  const IngestReport with = ingest_models({dir / "box.obj"}, dir / "lod.db", params, serial);
  params.chunk_lods = false;
  const IngestReport without = ingest_models({dir / "box.obj"}, dir / "plain.db", params, serial);
  EXPECT_GT(with.chunk_lods, 1u);
  EXPECT_EQ(without.chunk_lods, 0u);
  EXPECT_NE(with.content_hash, without.content_hash);
  {
    GeometryStore plain(dir / "plain.db");
    EXPECT_TRUE(plain.lods(1).empty());
    EXPECT_THROW(plain.load_lod(1, 1), std::runtime_error);
    GeometryStore store(dir / "lod.db");
    const std::vector<ChunkLodRef> levels = store.lods(1);
    ASSERT_EQ(levels.size(), with.chunk_lods);
    for (const ChunkLodRef& l : levels) {
      const auto chunk = store.load_lod(1, l.level);
      EXPECT_EQ(chunk->triangle_count(), l.triangle_count) << "level " << l.level;
      EXPECT_LT(chunk->triangle_count(), 1200u);
      EXPECT_LT(l.error, 0.1) << "level " << l.level;  // a 4 m box of flat walls
    }
    EXPECT_EQ(stored_content_hash(dir / "lod.db"), with.content_hash);
  }
  EXPECT_TRUE(check_store(dir / "lod.db").empty());
  {
    SqliteDb d(dir / "lod.db", SqliteDb::Mode::read_write_create);
    d.exec("UPDATE chunk_lods SET geometry = substr(geometry, 1, 40) WHERE chunk_id = 1 AND level = 1");
  }
  std::string problems;
  for (const StoreProblem& p : check_store(dir / "lod.db")) problems += describe(p) + "\n";
  EXPECT_NE(problems.find("chunk 1: level 1: "), std::string::npos) << problems;
  EXPECT_NE(problems.find("content hash mismatch"), std::string::npos) << problems;
  GeometryStore damaged(dir / "lod.db");
  EXPECT_THROW(damaged.load_lod(1, 1), std::runtime_error);
  {
    SqliteDb d(dir / "lod.db", SqliteDb::Mode::read_write_create);
    d.exec("DELETE FROM chunk_lods WHERE level = 2");
  }
  problems.clear();
  for (const StoreProblem& p : check_store_rows(dir / "lod.db")) problems += describe(p) + "\n";
  EXPECT_NE(problems.find("table chunk_lods has"), std::string::npos) << problems;
}

TEST_F(StoreCheck, AStoreWithoutRecordedCountsIsAcceptedAsBefore) {
  sql("DELETE FROM meta WHERE key = 'rows'");
  EXPECT_TRUE(check_store_rows(store()).empty());
  EXPECT_TRUE(check_store(store()).empty());
  EXPECT_EQ(bake().exit_code, 0);
}

TEST_F(StoreCheck, VerifyAndRenderSayWhenTheStoreIsNotTheOneBakedFrom) {
  ASSERT_EQ(bake().exit_code, 0);
  // Another model in a second store: its hash differs from the database's store_hash.
  std::ostringstream o;
  int next = 1;
  test::obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 2);
  test::write_text(dir_ / "other.obj", o.str());
  ASSERT_EQ(test::run_cellbake("ingest " + (dir_ / "other.obj").string() + " --store " +
                               (dir_ / "other.db").string())
                .exit_code,
            0);
  const std::string cells = (dir_ / "cells.db").string(), other = (dir_ / "other.db").string();
  const auto v = test::run_cellbake("verify --walk-seconds 0 " + cells + " --store " + other + " --report " +
                                    (dir_ / "report").string() + " --views-per-cell 1 --size 16x16 --quiet");
  EXPECT_NE(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("was baked from a geometry store with content hash"), std::string::npos)
      << v.output;
  const auto r =
      test::run_cellbake("render " + cells + " --store " + other +
                         " --eye 2,2,1 --look 3,2,1 --size 16x16 --out " + (dir_ / "view.png").string());
  EXPECT_NE(r.output.find("warning: " + cells + " was baked from a geometry store"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace cellbake
