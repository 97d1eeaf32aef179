// Status as an integrity check (issue #14, items 7-10): cells_total is the
// configuration's count; `status --check` recomputes content hashes and
// decodes blobs, `--repair` marks damaged cells pending; merge verifies shards
// and names them; damaged rows and meta values give located errors and never
// abort a whole status or verify; one bake per database (a lock file).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <sstream>
#include <thread>

#include "pipeline/ingest.h"
#include "stages/encode/encode.h"
#include "runner/merge_shards.h"
#include "storage/cell_check.h"
#include "storage/cell_content_hash.h"
#include "storage/cell_db.h"
#include "storage/cell_db_lock.h"
#include "storage/sqlite_db.h"
#include "tests/fixture_room_obj.h"
#include "viewer/decoded_cell.h"
#include "tests/fixture_box_store.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

// A 4 x 4 x 3 m box (19 200 triangles) with a pillar, and a 2 x 2 grid of
// 1.5 m cells in it (ids 1..4), baked small.
class Integrity : public ::testing::Test {
 protected:
  void SetUp() override { test::ingest_box_with_pillar(dir_.path()); }
  std::string db(const std::string& name) const { return (dir_ / name).string(); }
  test::CommandResult bake(const std::string& out, const std::string& extra = "") {
    return test::run_cellbake("bake --store " + db("s.db") + " --region=0.5,0.5,1,3.5,3.5,1 --cell-size 1.5 " +
                              "--face-size 16 --quiet --threads 1 --out " + db(out) + " " + extra);
  }
  static void sql(const std::string& database, const std::string& statement) {
    SqliteDb d(database, SqliteDb::Mode::read_write_create);
    d.exec(statement);
  }
  test::TempDir dir_;
};

std::string json_field(const std::string& json, const std::string& key) {
  const auto at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return "(missing)";
  const auto from = at + key.size() + 4;
  return json.substr(from, json.find_first_of(",\n}", from) - from);
}

TEST_F(Integrity, CellsTotalIsTheConfigurationsCountAndStatusShowsPending) {
  ASSERT_EQ(bake("part.db", "--cells 1-2").exit_code, 0);
  EXPECT_EQ(CellDb(db("part.db"), CellDb::Mode::read_only).meta("cells_total"), "4");
  const auto s = test::run_cellbake("status " + db("part.db") + " --json");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_EQ(json_field(s.output, "cells_total"), "4") << s.output;
  EXPECT_EQ(json_field(s.output, "cells_done"), "2") << s.output;
  EXPECT_EQ(json_field(s.output, "cells_pending"), "2") << s.output;

  // Two shards, one missing from the merge: its cells are pending in the merged database.
  ASSERT_EQ(bake("shard0.db", "--shard 0/2").exit_code, 0);
  ASSERT_EQ(bake("shard1.db", "--shard 1/2").exit_code, 0);
  const auto m = test::run_cellbake("merge " + db("merged.db") + " " + db("shard0.db") + " " + db("absent.db"));
  ASSERT_EQ(m.exit_code, 0) << m.output;
  const std::uint64_t in_shard0 = CellDb(db("shard0.db"), CellDb::Mode::read_only).cell_ids().size();
  const auto ms = test::run_cellbake("status " + db("merged.db") + " --json");
  EXPECT_EQ(json_field(ms.output, "cells_total"), "4") << ms.output;
  EXPECT_EQ(json_field(ms.output, "cells_pending"), std::to_string(4 - in_shard0)) << ms.output;
  // Both shards given to status: counted once each, nothing pending.
  const auto both = test::run_cellbake("status " + db("shard0.db") + " " + db("shard1.db") + " --json");
  EXPECT_EQ(json_field(both.output, "cells_total"), "4") << both.output;
  EXPECT_EQ(json_field(both.output, "cells_pending"), "0") << both.output;
}

TEST_F(Integrity, RecomputedContentHashesMatchTheBakesStamps) {
  ASSERT_EQ(bake("cells.db").exit_code, 0);
  CellDb cells(db("cells.db"), CellDb::Mode::read_only);
  ASSERT_EQ(cells.cell_ids().size(), 4u);
  for (std::int64_t id : cells.cell_ids()) {
    EXPECT_EQ(check_cell(cells, id), "") << "cell " << id;
    EXPECT_EQ(cell_content_hash(*cells.get_cell(id)), cells.get_cell(id)->content_hash);
  }
  const auto s = test::run_cellbake("status --check " + db("cells.db"));
  EXPECT_EQ(s.exit_code, 0) << s.output;
}

// A done cell with one sample of six decodable faces and its true content hash.
CellRow sound_cell(std::int64_t id) {
  CellRow c;
  c.id = id;
  c.status = "done";
  c.input_hash = c.cull_hash = "h" + std::to_string(id);
  c.near_chunks = {{7, 12, true}};
  SampleRow s;
  for (int f = 0; f < 6; ++f) {
    FaceMesh mesh;
    mesh.positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    mesh.uvs = {{0, 0}, {1, 0}, {0, 1}};
    mesh.indices = {0, 1, 2};
    const std::vector<Rgba8> pixels(16, Rgba8{10, 20, 30, 255});
    s.faces.push_back({f, "png", encode_image(pixels, 4, 4, {"png", 85}), encode_face_mesh(mesh, {}), 1, 0, 0});
  }
  c.samples = {s};
  c.content_hash = cell_content_hash(c);
  return c;
}

TEST_F(Integrity, CheckCellDecodesEveryBlobAndRecomputesTheHash) {
  {
    CellDb cells(db("cells.db"), CellDb::Mode::read_write);
    for (std::int64_t id = 1; id <= 6; ++id) cells.put_cell(sound_cell(id));
  }
  sql(db("cells.db"), "UPDATE faces SET mesh = substr(mesh, 1, 20) WHERE cell_id = 1 AND face = 2");
  sql(db("cells.db"), "DELETE FROM faces WHERE cell_id = 2");
  sql(db("cells.db"), "UPDATE faces SET image = substr(image, 1, 30) WHERE cell_id = 3 AND face = 0");
  sql(db("cells.db"), "UPDATE cells SET cull_half_size = 1 WHERE id = 4");  // decodes, but is not what was baked
  sql(db("cells.db"), "UPDATE cells SET near_chunks = x'07000000000000000c00000009' WHERE id = 5");
  CellDb cells(db("cells.db"), CellDb::Mode::read_only);
  EXPECT_NE(check_cell(cells, 1).find("sample 0 face 2 mesh: face mesh blob"), std::string::npos) << check_cell(cells, 1);
  EXPECT_EQ(check_cell(cells, 2), "sample 0 has 0 faces (6 expected, one per cube face)");
  EXPECT_NE(check_cell(cells, 3).find("sample 0 face 0 image: image blob"), std::string::npos) << check_cell(cells, 3);
  EXPECT_EQ(check_cell(cells, 4).rfind("content hash mismatch (stored ", 0), 0u) << check_cell(cells, 4);
  EXPECT_NE(check_cell(cells, 5).find("cells.db: cell 5: near_chunks: near-chunk list: bad flag"), std::string::npos)
      << check_cell(cells, 5);
  EXPECT_EQ(check_cell(cells, 6), "");
  EXPECT_EQ(check_cells(cells).size(), 5u);

  const auto check = test::run_cellbake("status --check " + db("cells.db"));
  EXPECT_NE(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find("cells.db: cell 2: sample 0 has 0 faces"), std::string::npos) << check.output;
  EXPECT_NE(check.output.find("5 damaged cell(s)"), std::string::npos) << check.output;
}

// Cuts the image blob of face `face` of sample 0 of cell `id` to `keep` bytes
// and stamps the cell's content hash anew, so only decoding can tell.
void cut_image_and_restamp(const std::string& database, std::int64_t id, int face, const std::string& keep) {
  {
    SqliteDb d(database, SqliteDb::Mode::read_write_create);
    d.exec("UPDATE faces SET image = substr(image, 1, " + keep + ") WHERE cell_id = " + std::to_string(id) +
           " AND sample_index = 0 AND face = " + std::to_string(face));
  }
  const std::string hash = cell_content_hash(*CellDb(database, CellDb::Mode::read_only).get_cell(id, true));
  SqliteDb d(database, SqliteDb::Mode::read_write_create);
  d.exec("UPDATE cells SET content_hash = '" + hash + "' WHERE id = " + std::to_string(id));
}

TEST_F(Integrity, CutOrWrongSizedFaceImagesAreDamagedThoughTheHashIsRestamped) {
  const std::vector<Rgba8> pixels = [] {
    std::vector<Rgba8> p;
    for (int i = 0; i < 32 * 32; ++i) p.push_back({std::uint8_t(i * 7), std::uint8_t(i / 5), std::uint8_t(i % 32 * 8), 255});
    return p;
  }();
  const std::vector<std::string> formats = {"jpeg", "png", "webp", "avif", "jxl"};
  {
    CellDb cells(db("cells.db"), CellDb::Mode::read_write);
    for (std::size_t k = 0; k < formats.size(); ++k) {
      CellRow c = sound_cell(std::int64_t(k) + 1);
      for (FaceRow& f : c.samples[0].faces)
        f.image_format = formats[k], f.image = encode_image(pixels, 32, 32, {formats[k], 80});
      c.content_hash = cell_content_hash(c);
      cells.put_cell(c);
    }
    CellRow small = sound_cell(6);  // one face 16 x 16 among 32 x 32 ones (restamped: only the size tells)
    for (FaceRow& f : small.samples[0].faces) f.image = encode_image(pixels, 32, 32, {"png", 80});
    small.samples[0].faces[4].image = encode_image(std::vector<Rgba8>(256, Rgba8{1, 2, 3, 255}), 16, 16, {"png", 80});
    small.content_hash = cell_content_hash(small);
    cells.put_cell(small);
    CellRow empty_face = sound_cell(7);  // a face without triangles keeps a 1 x 1 image: sound
    for (FaceRow& f : empty_face.samples[0].faces) f.image = encode_image(pixels, 32, 32, {"png", 80});
    empty_face.samples[0].faces[1].triangles = 0;
    empty_face.samples[0].faces[1].mesh = encode_face_mesh(FaceMesh{}, {});  // and no mesh (status --check counts them)
    empty_face.samples[0].faces[1].image = encode_image({Rgba8{0, 0, 0, 0}}, 1, 1, {"png", 80});
    empty_face.content_hash = cell_content_hash(empty_face);
    cells.put_cell(empty_face);
  }
  for (std::size_t k = 0; k < formats.size(); ++k) cut_image_and_restamp(db("cells.db"), std::int64_t(k) + 1, 3, "length(image) / 2");
  CellDb cells(db("cells.db"), CellDb::Mode::read_only);
  for (std::size_t k = 0; k < formats.size(); ++k) {
    const std::string problem = check_cell(cells, std::int64_t(k) + 1);
    EXPECT_EQ(problem.rfind("sample 0 face 3 image: image blob: ", 0), 0u) << formats[k] << ": " << problem;
  }
  EXPECT_EQ(check_cell(cells, 6), "sample 0 face 4 image: 16x16, not 32x32");
  EXPECT_EQ(check_cell(cells, 7), "");
}

TEST_F(Integrity, FacesWithoutTrianglesStoreNoImageAndAreCheckedForIt) {
  // A bake: every face without triangles stores kNoFaceImage and an empty blob, the others an image.
  ASSERT_EQ(bake("baked.db").exit_code, 0);
  {
    CellDb baked(db("baked.db"), CellDb::Mode::read_only);
    std::size_t none = 0;
    for (std::int64_t id : baked.cell_ids()) {
      const std::optional<CellRow> row = baked.get_cell(id, true);
      ASSERT_TRUE(row);
      for (const SampleRow& s : row->samples)
        for (const FaceRow& f : s.faces) {
          EXPECT_EQ(f.image_format == kNoFaceImage, f.triangles == 0) << "cell " << id << " face " << f.face;
          EXPECT_EQ(f.image.empty(), f.triangles == 0) << "cell " << id << " face " << f.face;
          none += f.image_format == kNoFaceImage;
        }
    }
    EXPECT_GT(none, 0u);
  }
  // Sound, and the two ways such a face can be damaged (restamped: only the check tells).
  const std::vector<Rgba8> pixels(32 * 32, Rgba8{90, 120, 150, 255});
  {
    CellDb cells(db("cells.db"), CellDb::Mode::read_write);
    for (std::int64_t id = 1; id <= 3; ++id) {
      CellRow c = sound_cell(id);
      for (FaceRow& f : c.samples[0].faces) f.image_format = "png", f.image = encode_image(pixels, 32, 32, {"png", 80});
      FaceRow& empty = c.samples[0].faces[2];
      empty.image_format = kNoFaceImage;
      empty.image.clear();
      empty.mesh = encode_face_mesh(FaceMesh{}, MeshEncodeParams{});
      empty.triangles = 0;
      if (id == 2) empty.image = {1, 2, 3};
      if (id == 3) empty.triangles = 5;
      c.content_hash = cell_content_hash(c);
      cells.put_cell(c);
    }
  }
  CellDb cells(db("cells.db"), CellDb::Mode::read_only);
  EXPECT_EQ(check_cell(cells, 1), "");
  EXPECT_EQ(check_cell(cells, 2), "sample 0 face 2: an image blob for a face that stores none");
  EXPECT_EQ(check_cell(cells, 3), "sample 0 face 2: 5 triangles but no image");
  EXPECT_NO_THROW(decode_cell(*cells.get_cell(1, true)));
  for (std::int64_t id : {2, 3}) {
    try {
      decode_cell(*cells.get_cell(id, true));
      ADD_FAILURE() << "cell " << id << " decoded";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("cell " + std::to_string(id) + " sample 0 face 2: stores no image"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST_F(Integrity, StatusCheckListsACellWithAHalvedJpegAndRepairRedoesIt) {
  // Depth meshes everywhere, so that faces have images to cut.
  ASSERT_EQ(bake("ref.db", "--set encode.image_format=jpeg --set far.choice=tdm").exit_code, 0);
  ASSERT_EQ(bake("cells.db", "--set encode.image_format=jpeg --set far.choice=tdm").exit_code, 0);
  std::int64_t victim = 0;
  int face = -1;
  {
    SqliteDb d(db("cells.db"), SqliteDb::Mode::read_only);
    SqliteStatement s(d, "SELECT cell_id, face FROM faces WHERE sample_index = 0 AND triangles > 0 "
                         "ORDER BY length(image) DESC, cell_id LIMIT 1");
    ASSERT_TRUE(s.step()) << "no face with an image";
    victim = s.column_int(0), face = int(s.column_int(1));
  }
  cut_image_and_restamp(db("cells.db"), victim, face, "length(image) / 2");
  const std::string where = "cell " + std::to_string(victim) + ": sample 0 face " + std::to_string(face) + " image: ";

  const auto check = test::run_cellbake("status --check " + db("cells.db"));
  EXPECT_NE(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find(where + "image blob: truncated jpg"), std::string::npos) << check.output;
  EXPECT_NE(check.output.find("1 damaged cell(s)"), std::string::npos) << check.output;

  const auto repair = test::run_cellbake("status --repair " + db("cells.db") + " --json");
  EXPECT_EQ(repair.exit_code, 0) << repair.output;
  EXPECT_EQ(json_field(repair.output, "cells_pending"), "1") << repair.output;
  EXPECT_FALSE(CellDb(db("cells.db"), CellDb::Mode::read_only).get_cell(victim, false).has_value());
  ASSERT_EQ(bake("cells.db", "--set encode.image_format=jpeg --set far.choice=tdm").exit_code, 0);
  EXPECT_EQ(CellDb(db("cells.db"), CellDb::Mode::read_only).totals().content_hash,
            CellDb(db("ref.db"), CellDb::Mode::read_only).totals().content_hash);
  EXPECT_EQ(test::run_cellbake("status --check " + db("cells.db")).exit_code, 0);
}

TEST_F(Integrity, StatusRepairMarksDamagedCellsPendingAndTheBakeRedoesThem) {
  ASSERT_EQ(bake("ref.db").exit_code, 0);
  ASSERT_EQ(bake("cells.db").exit_code, 0);
  std::int64_t sampled = 0;  // a cell with faces to damage
  for (std::int64_t id : CellDb(db("cells.db"), CellDb::Mode::read_only).cell_ids())
    if (!sampled && !CellDb(db("cells.db"), CellDb::Mode::read_only).get_cell(id, false)->samples.empty()) sampled = id;
  ASSERT_NE(sampled, 0) << "no cell with samples";
  const std::int64_t other = sampled == 1 ? 2 : 1;
  sql(db("cells.db"), "DELETE FROM faces WHERE cell_id = " + std::to_string(sampled));
  sql(db("cells.db"), "UPDATE cells SET cull_half_size = cull_half_size + 1 WHERE id = " + std::to_string(other));

  const auto plain = test::run_cellbake("status " + db("cells.db") + " --json");
  EXPECT_EQ(json_field(plain.output, "content_hash"),
            json_field(test::run_cellbake("status " + db("ref.db") + " --json").output, "content_hash"))
      << "without --check the stamps are trusted";
  const auto check = test::run_cellbake("status --check " + db("cells.db"));
  EXPECT_NE(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find("cell " + std::to_string(sampled) + ": sample 0 has 0 faces"), std::string::npos)
      << check.output;
  EXPECT_NE(check.output.find("cell " + std::to_string(other) + ": content hash mismatch"), std::string::npos)
      << check.output;

  const auto repair = test::run_cellbake("status --repair " + db("cells.db") + " --json");
  EXPECT_EQ(repair.exit_code, 0) << repair.output;
  EXPECT_EQ(json_field(repair.output, "cells_pending"), "2") << repair.output;
  EXPECT_EQ(CellDb(db("cells.db"), CellDb::Mode::read_only).cell_ids().size(), 2u);

  const auto rebake = bake("cells.db");
  ASSERT_EQ(rebake.exit_code, 0) << rebake.output;
  EXPECT_EQ(CellDb(db("cells.db"), CellDb::Mode::read_only).totals().content_hash,
            CellDb(db("ref.db"), CellDb::Mode::read_only).totals().content_hash);
  EXPECT_EQ(test::run_cellbake("status --check " + db("cells.db")).exit_code, 0);
}

TEST_F(Integrity, MergeRefusesADamagedShardNamingIt) {
  ASSERT_EQ(bake("shard0.db", "--shard 0/2").exit_code, 0);
  ASSERT_EQ(bake("shard1.db", "--shard 1/2").exit_code, 0);
  const std::int64_t victim = CellDb(db("shard1.db"), CellDb::Mode::read_only).cell_ids().front();
  sql(db("shard1.db"), "UPDATE cells SET cull_half_size = 0.125 WHERE id = " + std::to_string(victim));
  const auto m = test::run_cellbake("merge " + db("merged.db") + " " + db("shard0.db") + " " + db("shard1.db"));
  EXPECT_NE(m.exit_code, 0) << m.output;
  EXPECT_NE(m.output.find("shard1.db: 1 damaged cell(s)"), std::string::npos) << m.output;
  EXPECT_NE(m.output.find("cell " + std::to_string(victim) + ": content hash mismatch"), std::string::npos) << m.output;
  EXPECT_EQ(m.output.find("merged.db:"), std::string::npos) << "names the shard, not the output: " << m.output;
}

TEST_F(Integrity, ADamagedNearChunkListOrMetaValueGivesALocatedError) {
  ASSERT_EQ(bake("cells.db").exit_code, 0);
  sql(db("cells.db"), "UPDATE cells SET near_chunks = x'01000000000000000100000007' WHERE id = 2");
  const auto s = test::run_cellbake("status " + db("cells.db") + " --json");
  EXPECT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("cells.db: cell 2: near_chunks: near-chunk list: bad flag"), std::string::npos) << s.output;
  EXPECT_EQ(json_field(s.output, "cells_done"), "3") << s.output;
  EXPECT_EQ(json_field(s.output, "cells_damaged"), "1") << s.output;

  const auto v = test::run_cellbake("verify --walk-seconds 0 " + db("cells.db") + " --report " + db("report") +
                                    " --views-per-cell 1 --size 16x16 --threads 1 --quiet");
  EXPECT_NE(v.output.find("cells.db: cell 2: near_chunks"), std::string::npos) << v.output;
  EXPECT_NE(v.output.find("1 failed"), std::string::npos) << v.output;

  // A bake redoes the damaged cell rather than trusting its stamp.
  ASSERT_EQ(bake("cells.db").exit_code, 0);
  EXPECT_EQ(test::run_cellbake("status --check " + db("cells.db")).exit_code, 0);

  sql(db("cells.db"), "UPDATE meta SET value = 'lots' WHERE key = 'cells_total'");
  const auto garbage = test::run_cellbake("status " + db("cells.db"));
  EXPECT_NE(garbage.exit_code, 0);
  EXPECT_NE(garbage.output.find("cells.db: meta 'cells_total' is 'lots', not an unsigned integer"), std::string::npos)
      << garbage.output;
  sql(db("cells.db"), "UPDATE meta SET value = '2.0x' WHERE key = 'cell_size'");
  const auto vg = test::run_cellbake("verify --walk-seconds 0 " + db("cells.db") + " --report " + db("report2") + " --quiet");
  EXPECT_NE(vg.exit_code, 0);
  EXPECT_NE(vg.output.find("meta 'cell_size' is '2.0x', not a finite number"), std::string::npos) << vg.output;
}

TEST_F(Integrity, ASecondBakeOfADatabaseIsRefusedNamingThePid) {
  ASSERT_EQ(bake("cells.db", "--cells 1").exit_code, 0);
  {
    const CellDbLock held(db("cells.db"), "baked");
    const auto second = bake("cells.db");
    EXPECT_NE(second.exit_code, 0);
    EXPECT_NE(second.output.find("database " + db("cells.db") + " is being baked by pid " + std::to_string(getpid())),
              std::string::npos)
        << second.output;
    EXPECT_NE(test::run_cellbake("merge " + db("cells.db") + " " + db("other.db")).exit_code, 0);
  }
  EXPECT_FALSE(std::filesystem::exists(db("cells.db.lock")));  // removed on release
  // A holder killed with -9 leaves its lock file, but not the lock.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const CellDbLock held(db("cells.db"), "baked");
    pause();
    _exit(0);
  }
  for (int i = 0; i < 200 && !std::filesystem::exists(db("cells.db.lock")); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_THROW(CellDbLock(db("cells.db"), "baked"), std::runtime_error);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  EXPECT_TRUE(std::filesystem::exists(db("cells.db.lock")));
  const auto after = bake("cells.db");
  EXPECT_EQ(after.exit_code, 0) << after.output;
  EXPECT_EQ(CellDb(db("cells.db"), CellDb::Mode::read_only).totals().cells_done, 4u);
}

TEST_F(Integrity, ConcurrentOpensOfANewDatabaseCreateTheSchemaOnce) {
  for (int round = 0; round < 10; ++round) {
    const std::string path = db("new" + std::to_string(round) + ".db");
    std::vector<std::string> errors(4);
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        try {
          CellDb opened(path, CellDb::Mode::read_write);
        } catch (const std::exception& e) {
          errors[t] = e.what();
        }
      });
    for (auto& t : threads) t.join();
    for (const auto& e : errors) EXPECT_EQ(e, "") << "round " << round;
  }
}

// A writer killed inside a rollback-journal transaction (a bake killed while its
// new database switched to WAL, or any other tool) leaves a hot journal; a
// read-only open rolls it back as a writable one would, instead of failing
// with "attempt to write a readonly database".
TEST_F(Integrity, AReadOnlyOpenRecoversTheHotJournalOfAKilledWriter) {
  ASSERT_EQ(bake("cells.db").exit_code, 0);
  const std::string before = CellDb(db("cells.db"), CellDb::Mode::read_only).totals().content_hash;
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    SqliteDb writer(db("cells.db"), SqliteDb::Mode::read_write_create);
    writer.exec(
        "PRAGMA journal_mode=DELETE; PRAGMA cache_size=1; BEGIN; DELETE FROM cells; "
        "CREATE TABLE junk(x); WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 500) "
        "INSERT INTO junk SELECT randomblob(4000) FROM n;");
    _exit(0);  // killed mid-transaction: no commit, no rollback, no close
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_GT(std::filesystem::file_size(db("cells.db-journal")), 0u) << "the child left no hot journal";

  const auto st = test::run_cellbake("status " + db("cells.db"));
  EXPECT_EQ(st.exit_code, 0) << st.output;
  EXPECT_EQ(st.output.find("readonly"), std::string::npos) << st.output;
  CellDb reopened(db("cells.db"), CellDb::Mode::read_only);
  EXPECT_EQ(reopened.totals().content_hash, before);
  EXPECT_EQ(reopened.totals().cells_done, 4u);
  EXPECT_TRUE(reopened.integrity_ok());
  EXPECT_FALSE(std::filesystem::exists(db("cells.db-journal")) &&
               std::filesystem::file_size(db("cells.db-journal")) > 0);
}

}  // namespace
}  // namespace cellbake
