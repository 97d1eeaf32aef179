// Merging the shard databases of a distributed bake (no Slurm needed): the
// shard split, merged == single-machine bake, idempotency, refusal of shards
// from other inputs, tolerance of a missing shard, failed-vs-done precedence.
#include <gtest/gtest.h>

#include <fstream>

#include <memory>
#include <set>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/merge_shards.h"
#include "runner/parallel.h"
#include "runner/shards.h"
#include "storage/cell_content_hash.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "fixture_room_obj.h"
#include "test_support.h"

namespace cellbake {
namespace {

constexpr int kShards = 4;

std::filesystem::path make_store(const std::filesystem::path& dir, const std::string& name, bool pillars) {
  return test::ingest_room_store(dir, name, pillars);
}

BakeConfig room_config(const std::filesystem::path& store, const std::filesystem::path& db) {
  BakeConfig c;
  c.store = store;
  c.regions = {Box3d{{1, 1, 1.6}, {9, 9, 1.6}}};  // 4 x 4 cells of 2 m
  c.cell_size = 2.0;
  c.near_budget = 600;
  c.face_size = 32;
  c.image_format = "png";
  c.database = db;
  return c;
}

BakeOptions shard_options(int index, int count, const std::string& cells = "") {
  BakeOptions o;
  o.threads = 2;
  o.quiet = true;
  o.shard_index = index;
  o.shard_count = count;
  o.cells = cells;
  return o;
}

std::vector<std::filesystem::path> shard_paths(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> paths;
  for (int i = 0; i < kShards; ++i) paths.push_back(dir / ("shard_" + std::to_string(i) + ".db"));
  return paths;
}

std::string content_hash(const std::filesystem::path& db) {
  return CellDb(db, CellDb::Mode::read_only).totals().content_hash;
}

// One store, one single-machine bake and its four shards, shared by the suite
// (read only: tests merge into their own directories).
class Merge : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<test::TempDir>();
    const auto store = make_store(dir_->path(), "room", true);
    run_bake(room_config(store, dir_->path() / "single.db"), shard_options(0, 1));
    for (int i = 0; i < kShards; ++i) run_bake(room_config(store, shard_paths(dir_->path())[i]), shard_options(i, kShards));
  }
  static void TearDownTestSuite() { dir_.reset(); }
  static const std::filesystem::path& shared() { return dir_->path(); }
  static void ignore(const std::string&) {}

  static std::unique_ptr<test::TempDir> dir_;
};
std::unique_ptr<test::TempDir> Merge::dir_;

TEST_F(Merge, ShardsPartitionTheCellsEvenly) {
  GeometryStore store(shared() / "room.store.db");
  const auto cells = enumerate_cells(room_config("", "").regions, 2.0);
  ASSERT_EQ(cells.size(), 16u);
  std::set<std::int64_t> seen;
  for (int i = 0; i < kShards; ++i) {
    const auto part = shard_cells(cells, i, kShards, store);
    EXPECT_EQ(part.size(), 4u) << "shard " << i;  // equal per-cell constant dominates: 16 cells / 4
    for (const auto& c : part) EXPECT_TRUE(seen.insert(c.id).second) << "cell " << c.id << " in two shards";
    EXPECT_EQ(shard_cells(cells, i, kShards, store).front().id, part.front().id);  // deterministic
    EXPECT_EQ(CellDb(shard_paths(shared())[i], CellDb::Mode::read_only).cell_ids().size(), part.size());
  }
  EXPECT_EQ(seen.size(), 16u);
  EXPECT_THROW(shard_cells(cells, 4, 4, store), std::invalid_argument);
}

TEST_F(Merge, MergedShardsEqualASingleMachineBake) {
  test::TempDir dir;
  const MergeSummary s = merge_shards(dir / "merged.db", shard_paths(shared()), ignore);
  EXPECT_EQ(s.shards_merged, 4u);
  EXPECT_EQ(s.cells_copied, 16u);
  EXPECT_EQ(s.cells_done, 16u);
  EXPECT_EQ(s.cells_total, 16u);
  EXPECT_TRUE(s.missing_shards.empty());
  EXPECT_EQ(content_hash(dir / "merged.db"), content_hash(shared() / "single.db"));

  CellDb merged(dir / "merged.db", CellDb::Mode::read_only), single(shared() / "single.db", CellDb::Mode::read_only);
  EXPECT_TRUE(merged.integrity_ok());
  EXPECT_EQ(merged.meta("cells_total"), "16");
  EXPECT_EQ(merged.meta("config"), single.meta("config"));
  EXPECT_EQ(merged.meta("store_hash"), single.meta("store_hash"));
  // Blobs byte for byte, for one cell.
  const auto a = merged.get_cell(7), b = single.get_cell(7);
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->samples.size(), b->samples.size());
  ASSERT_EQ(a->samples[0].faces.size(), 6u);
  for (int f = 0; f < 6; ++f) {
    EXPECT_EQ(a->samples[0].faces[f].image, b->samples[0].faces[f].image);
    EXPECT_EQ(a->samples[0].faces[f].mesh, b->samples[0].faces[f].mesh);
  }

  // `cellbake status --json` over the merged database and over the shards agree with the single bake.
  const auto hash_of = [](const std::string& args) {
    const auto r = test::run_cellbake("status " + args + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const auto at = r.output.find("\"content_hash\": \"");
    return at == std::string::npos ? r.output : r.output.substr(at + 17, 32);
  };
  std::string shard_args;
  for (const auto& p : shard_paths(shared())) shard_args += p.string() + " ";
  EXPECT_EQ(hash_of((dir / "merged.db").string()), hash_of((shared() / "single.db").string()));
  EXPECT_EQ(hash_of(shard_args), hash_of((shared() / "single.db").string()));

  // A bake of the same config over the merged database has nothing left to do.
  const BakeSummary again = run_bake(room_config(shared() / "room.store.db", dir / "merged.db"), shard_options(0, 1));
  EXPECT_EQ(again.cells_up_to_date, 16u);
  EXPECT_EQ(again.cells_baked, 0u);
}

TEST_F(Merge, MergingTheSameShardsAgainChangesNothing) {
  test::TempDir dir;
  auto shards = shard_paths(shared());
  shards.push_back(shards[1]);  // the same shard twice in one call
  merge_shards(dir / "merged.db", shards, ignore);
  const std::string first = content_hash(dir / "merged.db");
  const MergeSummary again = merge_shards(dir / "merged.db", shard_paths(shared()), ignore);
  EXPECT_EQ(again.cells_copied, 0u);
  EXPECT_EQ(again.cells_unchanged, 16u);
  EXPECT_EQ(again.cells_total, 16u);
  EXPECT_EQ(content_hash(dir / "merged.db"), first);
  EXPECT_EQ(CellDb(dir / "merged.db", CellDb::Mode::read_only).meta("cells_total"), "16");

  // Shard by shard into the same output: the same result.
  for (const auto& p : shard_paths(shared())) merge_shards(dir / "incremental.db", {p}, ignore);
  EXPECT_EQ(content_hash(dir / "incremental.db"), first);
  EXPECT_EQ(CellDb(dir / "incremental.db", CellDb::Mode::read_only).meta("cells_total"), "16");
}

TEST_F(Merge, ResumesIntoTheEmptyFileOfAMergeKilledBeforeItsSchema) {
  test::TempDir dir;
  { std::ofstream empty(dir / "merged.db"); }  // what a merge killed right after creating its file leaves
  const MergeSummary s = merge_shards(dir / "merged.db", shard_paths(shared()), ignore);
  EXPECT_EQ(s.cells_copied, 16u);
  EXPECT_EQ(content_hash(dir / "merged.db"), content_hash(shared() / "single.db"));
  // Anything else that is not a cell database is still refused.
  std::ofstream(dir / "other.db") << "not a database at all, just text";
  EXPECT_THROW(merge_shards(dir / "other.db", shard_paths(shared()), ignore), std::runtime_error);
}

TEST_F(Merge, RefusesShardsFromOtherParametersOrStores) {
  test::TempDir dir;
  // Other parameters: JPEG instead of PNG (two cells of shard 2 are enough).
  BakeConfig jpeg = room_config(shared() / "room.store.db", dir / "jpeg_shard.db");
  jpeg.image_format = "jpeg";
  run_bake(jpeg, shard_options(2, kShards, "1-8"));
  auto shards = shard_paths(shared());
  shards[2] = dir / "jpeg_shard.db";
  try {
    merge_shards(dir / "merged.db", shards, ignore);
    FAIL() << "merged shards of different parameters";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("jpeg_shard.db"), std::string::npos) << m;
    EXPECT_NE(m.find("encode.image_format"), std::string::npos) << m;
    EXPECT_NE(m.find("different parameters"), std::string::npos) << m;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "merged.db"));  // refused before writing anything

  // Another geometry store, same parameters.
  const auto other = make_store(dir.path(), "empty_room", false);
  run_bake(room_config(other, dir / "other_store.db"), shard_options(0, kShards, "1-8"));
  shards = shard_paths(shared());
  shards[0] = dir / "other_store.db";
  try {
    merge_shards(dir / "merged.db", shards, ignore);
    FAIL() << "merged shards of different stores";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("other_store.db"), std::string::npos) << m;
    EXPECT_NE(m.find("different geometry store"), std::string::npos) << m;
  }

  // A good merge, then a mismatched shard into it: checked against the merged database.
  merge_shards(dir / "merged.db", shard_paths(shared()), ignore);
  EXPECT_THROW(merge_shards(dir / "merged.db", {dir / "jpeg_shard.db"}, ignore), std::runtime_error);
  EXPECT_EQ(content_hash(dir / "merged.db"), content_hash(shared() / "single.db"));
}

TEST_F(Merge, AMissingShardIsReportedAndTheRestIsUsable) {
  test::TempDir dir;
  auto shards = shard_paths(shared());
  shards[2] = dir / "shard_2.db";  // not baked (yet)
  std::vector<std::string> warnings;
  const MergeSummary s = merge_shards(dir / "merged.db", shards, [&](const std::string& w) { warnings.push_back(w); });

  GeometryStore store(shared() / "room.store.db");
  const auto lost = shard_cells(enumerate_cells(room_config("", "").regions, 2.0), 2, kShards, store);
  std::vector<std::int64_t> lost_ids;
  for (const auto& c : lost) lost_ids.push_back(c.id);
  EXPECT_EQ(s.missing_shards, std::vector<std::string>{shards[2].string()});
  EXPECT_EQ(s.missing_cells, lost_ids);
  EXPECT_EQ(s.cells_done, 16u - lost.size());
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("shard_2.db"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[1].find(format_cell_selection(lost_ids)), std::string::npos) << warnings[1];

  // The shard is baked later (its array task rerun) and merged in: complete.
  std::filesystem::copy_file(shard_paths(shared())[2], shards[2]);
  const MergeSummary done = merge_shards(dir / "merged.db", shards, ignore);
  EXPECT_TRUE(done.missing_shards.empty());
  EXPECT_EQ(done.cells_copied, lost.size());
  EXPECT_EQ(done.cells_total, 16u);
  EXPECT_EQ(content_hash(dir / "merged.db"), content_hash(shared() / "single.db"));

  // No shard at all is an error, not an empty database.
  EXPECT_THROW(merge_shards(dir / "nothing.db", {dir / "a.db", dir / "b.db"}, ignore), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir / "nothing.db"));
}

// A hand-made cell row; `done` cells carry their content hash (merge verifies
// it; no samples, so no blobs to decode), failed ones an error and a sample.
CellRow cell(std::int64_t id, bool done, const std::string& tag) {
  CellRow c;
  c.id = id;
  c.status = done ? "done" : "failed";
  c.error = done ? "" : "cell " + std::to_string(id) + " failed in stage sample: " + tag;
  c.input_hash = "input-" + std::to_string(id);
  c.cull_hash = "cull-" + std::to_string(id);
  c.cull_half_size = double(tag.size()) + tag[0] / 256.0;  // the tag shows in the content
  if (done) {
    c.content_hash = cell_content_hash(c);
    return c;
  }
  SampleRow sample;
  sample.eye = {1, 2, 3};
  sample.faces = {FaceRow{0, "png", {1, 2, 3}, {4, 5}, 2, 0, 0}};
  c.samples = {sample};
  return c;
}

void write_shard(const std::filesystem::path& path, const std::vector<CellRow>& cells) {
  CellDb db(path, CellDb::Mode::read_write);
  db.set_meta("store_hash", "store");
  db.set_meta("config", "cells.size=1\n");
  db.set_meta("cells_total", std::to_string(cells.size()));
  for (const auto& c : cells) db.put_cell(c);
}

TEST(MergeCells, FailedCellsAreCopiedButNeverReplaceDoneOnes) {
  test::TempDir dir;
  write_shard(dir / "a.db", {cell(1, true, "a"), cell(2, false, "a")});
  write_shard(dir / "b.db", {cell(1, false, "b"), cell(3, false, "b")});
  MergeSummary s = merge_shards(dir / "merged.db", {dir / "a.db", dir / "b.db"}, [](const std::string&) {});
  EXPECT_EQ(s.cells_kept_done, 1u);
  EXPECT_EQ(s.cells_done, 1u);
  EXPECT_EQ(s.cells_failed, 2u);
  EXPECT_EQ(s.cells_total, 4u);  // 2 + 2 as the shards say (cell 1 counted by both)
  {
    CellDb m(dir / "merged.db", CellDb::Mode::read_only);
    EXPECT_EQ(m.get_cell(1)->status, "done");
    EXPECT_EQ(m.get_cell(1)->content_hash, cell(1, true, "a").content_hash);
    EXPECT_EQ(m.get_cell(2)->status, "failed");
    EXPECT_NE(m.get_cell(3)->error.find("stage sample"), std::string::npos);
    ASSERT_EQ(m.get_cell(3)->samples.size(), 1u);
    EXPECT_EQ(m.get_cell(3)->samples[0].faces[0].image, (std::vector<std::uint8_t>{1, 2, 3}));
  }
  // A rerun fixes cell 2: the done row replaces the failed one.
  write_shard(dir / "c.db", {cell(2, true, "c")});
  s = merge_shards(dir / "merged.db", {dir / "c.db"}, [](const std::string&) {});
  EXPECT_EQ(s.cells_copied, 1u);
  EXPECT_EQ(s.cells_done, 2u);
  EXPECT_EQ(CellDb(dir / "merged.db", CellDb::Mode::read_only).get_cell(2)->content_hash, cell(2, true, "c").content_hash);
  EXPECT_TRUE(CellDb(dir / "merged.db", CellDb::Mode::read_only).integrity_ok());
}

TEST(MergeCells, RefusesToMergeADatabaseIntoItself) {
  test::TempDir dir;
  write_shard(dir / "a.db", {cell(1, true, "a")});
  EXPECT_THROW(merge_shards(dir / "a.db", {dir / "a.db"}, [](const std::string&) {}), std::runtime_error);
}

TEST(MergeCells, FormatsCellSelections) {
  EXPECT_EQ(format_cell_selection({}), "");
  EXPECT_EQ(format_cell_selection({4}), "4");
  EXPECT_EQ(format_cell_selection({1, 2, 3, 7, 9, 10}), "1-3,7,9-10");
}

}  // namespace
}  // namespace cellbake
