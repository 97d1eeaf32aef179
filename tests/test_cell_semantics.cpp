// Every column a reader uses is verified (issue #41, item 3) and a cell's
// content is validated against the store it was baked from (issue #37, item
// 3): damage applied with SQL and the content hash restamped, as a buggy or
// hostile shard would send it, is found by `status --check` with the cell or
// meta key named, and `merge` refuses the shard.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/cell_database_check.h"
#include "runner/merge_shards.h"
#include "stages/encode/encode.h"
#include "stages/encode/encode_triangle_list.h"
#include "storage/cell_check.h"
#include "storage/cell_content_hash.h"
#include "storage/cell_db.h"
#include "storage/sqlite_db.h"
#include "tests/fixture_box_store.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

// The 4 x 4 x 3 m box with a pillar, 2 x 2 cells of 1.5 m baked with the far
// choice (far.db: exact far geometry rows; lod.db: the store's simplified
// chunk levels wherever they cost less) or with depth meshes only (tdm.db: face
// meshes), each once per test program and only when a test asks for it (CTest
// runs each test in a program of its own).
class CellSemantics : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { dir_ = new test::TempDir; }
  static void bake(const std::string& name) {
    if (std::filesystem::exists(path(name))) return;
    if (!std::filesystem::exists(path("s.db"))) test::ingest_box_with_pillar(dir_->path());
    ASSERT_EQ(
        test::run_cellbake("bake --store " + path("s.db") +
                           " --region=0.5,0.5,1,3.5,3.5,1 --cell-size 1.5 --face-size 32 --near-budget 1000 "
                           "--quiet --threads 2 --out " +
                           path(name) +
                           (name == "tdm.db"   ? " --set far.choice=tdm"
                            : name == "far.db" ? " --set far.lod_error_px=0"  // exact rows: triangle lists
                                               : " --set far.lod_replaces_exact=on"))  // level rows
            .exit_code,
        0);
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string path(const std::string& name) { return (dir_->path() / name).string(); }

  // A copy of baked database `from` as `to`, `statements` applied, cell `id`'s content hash restamped.
  static std::string damaged(const std::string& from, const std::string& to, std::int64_t id,
                             const std::vector<std::string>& statements) {
    bake(from);
    std::filesystem::copy_file(path(from), path(to), std::filesystem::copy_options::overwrite_existing);
    {
      SqliteDb d(path(to), SqliteDb::Mode::read_write_create);
      for (const auto& s : statements) d.exec(s);
    }
    const std::string hash = cell_content_hash(*CellDb(path(to), CellDb::Mode::read_only).get_cell(id, true));
    SqliteDb d(path(to), SqliteDb::Mode::read_write_create);
    d.exec("UPDATE cells SET content_hash = '" + hash + "' WHERE id = " + std::to_string(id));
    return path(to);
  }

  // What check_cell says of cell `id` with the database's own context (grid, store).
  static std::string problem(const std::string& database, std::int64_t id) {
    const CellDb db(database, CellDb::Mode::read_only);
    const CellCheckSetup setup = cell_check_setup(db);
    EXPECT_TRUE(setup.note.empty()) << setup.note;
    return check_cell(db, id, setup.context);
  }

  // check_cell (what `status --check` runs) names `what`, and with `command`
  // so does `status --check` itself, naming the cell, exit non-zero; merging
  // the shard is refused naming it.
  enum class Command { no, status };
  static void expect_found(const std::string& database, std::int64_t id, const std::string& what,
                           Command command = Command::no) {
    const std::string found = problem(database, id);
    EXPECT_NE(found.find(what), std::string::npos) << "cell " << id << ": " << found;
    if (command == Command::status) {
      const auto status = test::run_cellbake("status --check " + database);
      EXPECT_NE(status.exit_code, 0) << status.output;
      EXPECT_NE(status.output.find("cell " + std::to_string(id) + ": "), std::string::npos) << status.output;
      EXPECT_NE(status.output.find(what), std::string::npos) << status.output;
    }
    const std::string out = database + ".merged";
    try {
      merge_shards(out, {database}, [](const std::string&) {}, /*check_images=*/true);
      ADD_FAILURE() << database << ": merge accepted a damaged shard";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }

  static std::int64_t far_cell() {
    bake("far.db");
    SqliteDb d(path("far.db"), SqliteDb::Mode::read_only);
    SqliteStatement s(d, "SELECT cell_id FROM far_geometry WHERE whole = 0 ORDER BY cell_id LIMIT 1");
    return s.step() ? s.column_int(0) : 0;
  }
  static std::int64_t far_chunk(std::int64_t cell) {
    SqliteDb d(path("far.db"), SqliteDb::Mode::read_only);
    SqliteStatement s(d, "SELECT chunk_id FROM far_geometry WHERE whole = 0 AND cell_id = " +
                             std::to_string(cell) + " ORDER BY chunk_id LIMIT 1");
    return s.step() ? s.column_int(0) : 0;
  }

  static test::TempDir* dir_;
};
test::TempDir* CellSemantics::dir_ = nullptr;

TEST_F(CellSemantics, BakedCellsAndTheirMergePass) {
  for (const char* name : {"far.db", "tdm.db", "lod.db"}) {
    bake(name);
    const CellDb db(path(name), CellDb::Mode::read_only);
    EXPECT_TRUE(check_database_meta(db).empty()) << name;
    for (std::int64_t id : db.cell_ids()) EXPECT_EQ(problem(path(name), id), "") << name << " cell " << id;
    EXPECT_EQ(test::run_cellbake("status --check " + path(name)).exit_code, 0) << name;
  }
  EXPECT_NO_THROW(merge_shards(path("merged.db"), {path("far.db")}, [](const std::string&) {}));
  ASSERT_NE(far_cell(), 0) << "the bake kept no far geometry: nothing below would test it";
  SqliteDb d(path("lod.db"), SqliteDb::Mode::read_only);
  SqliteStatement levels(d, "SELECT count(*) FROM far_geometry WHERE level > 0");
  ASSERT_TRUE(levels.step());
  EXPECT_GT(levels.column_int(0), 0) << "the bake drew no chunk at a simplified level";
}

TEST_F(CellSemantics, MovedCellBoundsAreFoundAgainstTheGrid) {
  const std::string db = damaged("far.db", "moved.db", 2,
                                 {"UPDATE cells SET min_x = min_x + 100, max_x = max_x + 100 WHERE id = 2"});
  expect_found(db, 2, "are not the grid's", Command::status);
  const std::string g = damaged("far.db", "gx.db", 3, {"UPDATE cells SET gx = 7 WHERE id = 3"});
  expect_found(g, 3, "is not the grid's region");
}

TEST_F(CellSemantics, MetaValuesAreParsedFiniteAndInRange) {
  struct Case {
    std::string statement, key, what;
  };
  for (const Case& c :
       {Case{"UPDATE meta SET value = replace(value, 'view.far_budget=100000', 'view.far_budget=1e300') "
             "WHERE key = 'config'",
             "config", "view.far_budget"},
        Case{"UPDATE meta SET value = replace(value, 'shading.ambient=', 'shading.ambient=nan') WHERE key = "
             "'config'",
             "config", "shading.ambient"},
        Case{"UPDATE meta SET value = value || 'region=1,2,3' || char(10) WHERE key = 'config'", "config",
             "region"},
        Case{"UPDATE meta SET value = '-2' WHERE key = 'cell_size'", "cell_size", "not a positive cell size"},
        Case{"UPDATE meta SET value = '3.0' WHERE key = 'cell_size'", "cell_size",
             "not the config's cells.size"},
        Case{"UPDATE meta SET value = 'x' WHERE key = 'up'", "up", "is not z or y"},
        Case{"UPDATE meta SET value = 'not a hash' WHERE key = 'store_hash'", "store_hash",
             "not a content hash"}}) {
    bake("far.db");
    std::filesystem::copy_file(path("far.db"), path("meta.db"),
                               std::filesystem::copy_options::overwrite_existing);
    {
      SqliteDb d(path("meta.db"), SqliteDb::Mode::read_write_create);
      d.exec(c.statement);
    }
    const auto problems = check_database_meta(CellDb(path("meta.db"), CellDb::Mode::read_only));
    ASSERT_FALSE(problems.empty()) << c.statement;
    EXPECT_EQ(problems.front().key, c.key) << c.statement;
    EXPECT_NE(problems.front().reason.find(c.what), std::string::npos) << problems.front().reason;
    try {
      merge_shards(path("meta.db.merged"), {path("meta.db")}, [](const std::string&) {});
      ADD_FAILURE() << c.statement << ": merge accepted the shard";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("meta '" + c.key + "': "), std::string::npos) << e.what();
    }
  }
  // status --check names the key, exit non-zero (the last case's database).
  const auto status = test::run_cellbake("status --check " + path("meta.db"));
  EXPECT_NE(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("meta.db: meta 'store_hash': "), std::string::npos) << status.output;
}

TEST_F(CellSemantics, TruncatedOrEmptiedNearListsAreFoundAgainstTheStore) {
  bake("far.db");
  const CellRow row = *CellDb(path("far.db"), CellDb::Mode::read_only).get_cell(1, true);
  ASSERT_GE(row.near_chunks.size(), 2u);
  std::vector<NearChunkRow> first = {row.near_chunks.front()};
  std::string hex;
  for (std::uint8_t b : pack_near_chunks(first)) {
    char buf[3];
    std::snprintf(buf, sizeof buf, "%02x", b);
    hex += buf;
  }
  expect_found(damaged("far.db", "cut.db", 1, {"UPDATE cells SET near_chunks = x'" + hex + "' WHERE id = 1"}),
               1, "near list holds", Command::status);
  expect_found(damaged("far.db", "empty.db", 1,
                       {"UPDATE cells SET near_chunks = x'', near_triangles = 0 WHERE id = 1"}),
               1, "near list is empty, the cull box meets");
}

TEST_F(CellSemantics, FarGeometryIsCheckedAgainstItsChunks) {
  const std::int64_t cell = far_cell(), chunk = far_chunk(cell);
  ASSERT_NE(chunk, 0);
  const std::string where =
      " WHERE cell_id = " + std::to_string(cell) + " AND chunk_id = " + std::to_string(chunk);
  std::string list_hex;
  for (std::uint8_t b : encode_triangle_list(std::vector<std::uint32_t>{0, 5000000})) {
    char buf[3];
    std::snprintf(buf, sizeof buf, "%02x", b);
    list_hex += buf;
  }
  const std::string keep_sum =
      "UPDATE cells SET far_geometry_triangles = (SELECT sum(triangles) FROM far_geometry "
      "WHERE cell_id = " +
      std::to_string(cell) + ") WHERE id = " + std::to_string(cell);
  expect_found(
      damaged("far.db", "past.db", cell,
              {"UPDATE far_geometry SET geometry = x'" + list_hex + "', triangles = 2" + where, keep_sum}),
      cell, "triangle 5000000 is past the chunk's", Command::status);
  expect_found(damaged("far.db", "negative.db", cell, {"UPDATE far_geometry SET chunk_id = -5" + where}),
               cell, "far geometry of chunk -5: chunk ids are positive");
  expect_found(damaged("far.db", "missing.db", cell, {"UPDATE far_geometry SET chunk_id = 99999" + where}),
               cell, "chunk 99999 does not exist");
  expect_found(damaged("far.db", "whole.db", cell,
                       {"UPDATE far_geometry SET chunk_id = 88888, whole = 1, geometry = x''" + where}),
               cell, "chunk 88888 does not exist");
  expect_found(damaged("far.db", "inverted.db", cell, {"UPDATE far_geometry SET min_x = max_x + 1" + where}),
               cell, "are inverted or not finite");
  expect_found(damaged("far.db", "moved.db", cell, {"UPDATE far_geometry SET min_x = min_x - 1" + where}),
               cell, "are not those of its triangles");
  expect_found(damaged("far.db", "deleted.db", cell, {"DELETE FROM far_geometry" + where}), cell,
               "(rows deleted or added)");
}

TEST_F(CellSemantics, GeometryTilesThatDrawNoFarTrianglesNeedNoRows) {
  // What a cell of the 82 M plant baked: tiles drawn as geometry whose seen
  // triangles all belong to near chunks (in the seam shell), so its far
  // choice rows record 0 geometry triangles and it has no far geometry rows.
  const std::int64_t cell = far_cell();
  ASSERT_NE(cell, 0);
  const std::string where = " WHERE cell_id = " + std::to_string(cell);
  const std::string db = damaged("far.db", "no-far-triangles.db", cell,
                                 {"DELETE FROM far_geometry" + where, "UPDATE far_choice SET geometry_triangles = 0" + where,
                                  "UPDATE cells SET far_geometry_triangles = 0 WHERE id = " + std::to_string(cell)});
  {
    SqliteDb d(db, SqliteDb::Mode::read_only);
    SqliteStatement s(d, "SELECT count(*) FROM far_choice WHERE geometry_tiles != 0 AND cell_id = " + std::to_string(cell));
    ASSERT_TRUE(s.step());
    ASSERT_GT(s.column_int(0), 0);
  }
  EXPECT_EQ(problem(db, cell), "");
  // With a face's geometry triangles recorded, the missing rows are damage.
  expect_found(damaged("far.db", "no-rows.db", cell,
                       {"DELETE FROM far_geometry" + where,
                        "UPDATE cells SET far_geometry_triangles = 0 WHERE id = " + std::to_string(cell)}),
               cell, "far choice draws far triangles in geometry tiles but the cell has no far geometry rows");
}

TEST_F(CellSemantics, FaceMeshesAreCheckedAgainstTheirFaceAndTheFarChoice) {
  // Swapped between faces 0 and 2 (triangle counts too): each is coded for the other face.
  const std::string swap =
      "UPDATE faces SET mesh = (SELECT f.mesh FROM faces f WHERE f.cell_id = faces.cell_id AND "
      "f.sample_index = 0 AND "
      "f.face = 2 - faces.face), triangles = (SELECT f.triangles FROM faces f WHERE f.cell_id = "
      "faces.cell_id AND "
      "f.sample_index = 0 AND f.face = 2 - faces.face) WHERE cell_id = 1 AND sample_index = 0 AND face IN "
      "(0, 2)";
  expect_found(damaged("tdm.db", "swapped.db", 1, {swap}), 1,
               "mesh: the mesh of face 2 (swapped between faces?)", Command::status);
  expect_found(
      damaged("tdm.db", "counted.db", 1,
              {"UPDATE far_choice SET tdm_triangles = tdm_triangles + 7 WHERE cell_id = 1 AND face = 0"}),
      1, "face 0: the samples' meshes hold");
  expect_found(damaged("tdm.db", "tiles.db", 1,
                       {"UPDATE far_choice SET geometry_tiles = 65535 WHERE cell_id = 1 AND face = 0"}),
               1, "lie within the face's geometry tiles");
}

TEST_F(CellSemantics, VerifyLodCutMeasuresEveryViewAgainstTheStoresLevels) {
  bake("lod.db");
  const std::string report = path("cut-report");
  const auto v = test::run_cellbake("verify --walk-seconds 0 " + path("lod.db") + " --report " + report +
                                    " --views-per-cell 2 --size 32x24 --threads 1 --quiet --lod-cut");
  ASSERT_EQ(v.exit_code, 0) << v.output;
  std::ifstream in(report + "/report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  std::size_t views = 0;
  for (const auto& cell : j.at("cells"))
    for (const auto& view : cell.at("views")) {
      ++views;
      ASSERT_TRUE(view.contains("psnr_db_cut")) << view.dump();
      if (view.at("truth_blank").get<bool>()) continue;
      // The 1 px cut never draws more than the truth; the cut with the cell's triangles fits them.
      EXPECT_LE(view.at("triangles_cut_1px").get<double>(), view.at("triangles_truth").get<double>());
      EXPECT_GE(view.at("cut_error_px").get<double>(), 0.0);
      // The finest cut within the cell's triangles: when the 1 px cut fits them, it is at most 1 px.
      if (view.at("triangles_cut_1px").get<double>() <= view.at("triangles_impostor").get<double>())
        EXPECT_LE(view.at("cut_error_px").get<double>(), 1.0) << view.dump();
    }
  EXPECT_GE(views, 8u);
  EXPECT_GT(j.at("summary").at("psnr_gain_over_cut").at("count").get<int>(), 0);
}

TEST_F(CellSemantics, AValidImageOfAnotherFormatInAFacesPlaceIsFound) {
  // A PNG of zeros, the face's size, for an AVIF face (the baked format): it
  // decodes, so only its format tells it from the image baked there.
  const std::vector<Rgba8> zeros(32 * 32, Rgba8{0, 0, 0, 0});
  ImageEncodeParams png;
  png.format = "png";
  std::string hex;
  for (std::uint8_t b : encode_image(zeros, 32, 32, png)) {
    char buf[3];
    std::snprintf(buf, sizeof buf, "%02x", b);
    hex += buf;
  }
  bake("tdm.db");
  SqliteDb d(path("tdm.db"), SqliteDb::Mode::read_only);
  SqliteStatement s(d, "SELECT face FROM faces WHERE cell_id = 1 AND sample_index = 0 AND image_format = 'avif' "
                       "ORDER BY face LIMIT 1");
  ASSERT_TRUE(s.step());
  const std::string face = std::to_string(s.column_int(0));
  expect_found(damaged("tdm.db", "zeros.db", 1,
                       {"UPDATE faces SET image = x'" + hex + "' WHERE cell_id = 1 AND sample_index = 0 AND face = " +
                        face}),
               1, "face " + face + " image: a png image, but the face's row says avif", Command::status);
}

TEST_F(CellSemantics, AnImageOfTheRightFormatAndSizeThatIsNotTheModelIsFound) {
  // An AVIF of zeros, the face's size, for the AVIF face of cell 1's first
  // sample with the most triangles: it decodes as the row says, so only the
  // model resampled at the sample's eye tells it from the image baked there.
  bake("tdm.db");
  std::string face;
  {
    SqliteDb d(path("tdm.db"), SqliteDb::Mode::read_only);
    SqliteStatement s(d, "SELECT face FROM faces WHERE cell_id = 1 AND sample_index = 0 AND image_format = 'avif' "
                         "ORDER BY triangles DESC, face LIMIT 1");
    ASSERT_TRUE(s.step());
    face = std::to_string(s.column_int(0));
  }
  ImageEncodeParams avif;
  avif.format = "avif";
  std::string hex;
  for (std::uint8_t b : encode_image(std::vector<Rgba8>(32 * 32, Rgba8{0, 0, 0, 255}), 32, 32, avif)) {
    char buf[3];
    std::snprintf(buf, sizeof buf, "%02x", b);
    hex += buf;
  }
  const std::string black =
      damaged("tdm.db", "black.db", 1,
              {"UPDATE faces SET image = x'" + hex + "' WHERE cell_id = 1 AND sample_index = 0 AND face = " + face});
  expect_found(black, 1, "sample 0 face " + face + " image: mean colour (0, 0, 0) at ", Command::status);
  // A merge compares images with the model only when asked (`merge --check-images`).
  EXPECT_NO_THROW(merge_shards(path("black-merged.db"), {black}, [](const std::string&) {}));
}

TEST_F(CellSemantics, VerifyFallsBackPerCellOnDamagedFarGeometry) {

  bake("far.db");
  std::vector<std::int64_t> cells;
  {
    SqliteDb d(path("far.db"), SqliteDb::Mode::read_only);
    SqliteStatement s(d, "SELECT DISTINCT cell_id FROM far_geometry WHERE whole = 0 ORDER BY cell_id");
    while (s.step()) cells.push_back(s.column_int(0));
  }
  ASSERT_GE(cells.size(), 3u);
  const auto in = [](std::int64_t cell) { return " WHERE cell_id = " + std::to_string(cell); };
  std::string list_hex;
  for (std::uint8_t b : encode_triangle_list(std::vector<std::uint32_t>{5000000})) {
    char buf[3];
    std::snprintf(buf, sizeof buf, "%02x", b);
    list_hex += buf;
  }
  // Three cells damaged three ways: triangles past their chunk's end, a missing chunk, inverted bounds.
  const std::string db =
      damaged("far.db", "readers.db", cells[0],
              {"UPDATE far_geometry SET geometry = x'" + list_hex + "', triangles = 1" + in(cells[0]),
               "UPDATE far_geometry SET chunk_id = -chunk_id" + in(cells[1]),
               "UPDATE far_geometry SET min_x = max_x + 1" + in(cells[2])});
  const auto v = test::run_cellbake("verify --walk-seconds 0 " + db + " --report " + path("report") +
                                    " --views-per-cell 1 --size 16x16 --threads 1 --quiet");
  EXPECT_NE(v.exit_code, 0) << v.output;  // failed cells are an error, after every other cell was verified
  EXPECT_NE(v.output.find("verified 4 cells (4 rendered, 0 reused, 3 failed)"), std::string::npos)
      << v.output;
  for (std::int64_t cell : cells)
    if (cell <= cells[2])
      EXPECT_NE(
          v.output.find("cell " + std::to_string(cell) + ": cell " + std::to_string(cell) + " far geometry"),
          std::string::npos)
          << v.output;
  EXPECT_TRUE(std::filesystem::exists(dir_->path() / "report" / "report.html"));
}

}  // namespace
}  // namespace cellbake
