// Cell database schema v5 (v3: several samples per cell; v4: exact far
// geometry per face tile; v5: a far geometry row's simplified level): version
// 2 and 4 databases, as cellbake wrote them before, open read-only as they are
// (far rows at level 0) and migrate in place when opened read-write, keeping
// their cells; merge refuses to mix versions.
#include <gtest/gtest.h>

#include "storage/cell_content_hash.h"
#include "storage/cell_db.h"
#include "storage/cell_db_merge.h"
#include "storage/sqlite_db.h"
#include "test_support.h"

namespace cellbake {
namespace {

// A version 2 database with one done cell of one sample (one face).
void write_v2_database(const std::filesystem::path& file) {
  SqliteDb db(file, SqliteDb::Mode::read_write_create);
  db.exec(R"sql(
CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE cells(
  id INTEGER PRIMARY KEY, region INTEGER NOT NULL, gx INTEGER NOT NULL, gy INTEGER NOT NULL, gz INTEGER NOT NULL,
  min_x REAL, min_y REAL, min_z REAL, max_x REAL, max_y REAL, max_z REAL,
  status TEXT NOT NULL, error TEXT NOT NULL DEFAULT '',
  input_hash TEXT NOT NULL, cull_hash TEXT NOT NULL, content_hash TEXT NOT NULL,
  cull_half_size REAL, near_triangles INTEGER, near_chunks BLOB,
  far_triangles INTEGER, bytes INTEGER, max_boundary_error_px REAL, max_depth_error REAL,
  stage_seconds TEXT NOT NULL DEFAULT '{}');
CREATE TABLE samples(
  cell_id INTEGER NOT NULL REFERENCES cells(id) ON DELETE CASCADE, sample_index INTEGER NOT NULL,
  eye_x REAL NOT NULL, eye_y REAL NOT NULL, eye_z REAL NOT NULL, parent INTEGER NOT NULL,
  PRIMARY KEY(cell_id, sample_index));
CREATE TABLE faces(
  cell_id INTEGER NOT NULL, sample_index INTEGER NOT NULL, face INTEGER NOT NULL,
  image_format TEXT NOT NULL, image BLOB NOT NULL, mesh BLOB NOT NULL,
  triangles INTEGER NOT NULL, boundary_error_px REAL, depth_error REAL,
  PRIMARY KEY(cell_id, sample_index, face),
  FOREIGN KEY(cell_id, sample_index) REFERENCES samples(cell_id, sample_index) ON DELETE CASCADE);
INSERT INTO meta VALUES('kind', 'cellbake-cell-database');
INSERT INTO cells VALUES(7, 0, 1, 2, 0, 0, 0, 0, 2, 2, 2, 'done', '', 'in', 'cull', 'content', 1.5, 10, x'', 20,
                         30, 0.4, 0.01, '{"sample": 1.0}');
INSERT INTO samples VALUES(7, 0, 1, 1, 1, -1);
INSERT INTO faces VALUES(7, 0, 3, 'png', x'0102', x'0304', 20, 0.4, 0.01);
PRAGMA user_version = 2;
)sql");
}

// A version 4 database (the v3 and v4 migrations over write_v2_database's)
// whose cell 7 has one far geometry row (chunk 11, whole, 6 triangles).
void write_v4_database(const std::filesystem::path& file) {
  write_v2_database(file);
  SqliteDb db(file, SqliteDb::Mode::read_write_create);
  db.exec(R"sql(
ALTER TABLE samples ADD COLUMN void_after REAL NOT NULL DEFAULT -1;
ALTER TABLE samples ADD COLUMN covered_pixels INTEGER NOT NULL DEFAULT 0;
ALTER TABLE samples ADD COLUMN removed_pixels INTEGER NOT NULL DEFAULT 0;
ALTER TABLE samples ADD COLUMN seconds REAL NOT NULL DEFAULT 0;
ALTER TABLE cells ADD COLUMN far_geometry_triangles INTEGER NOT NULL DEFAULT 0;
CREATE TABLE far_geometry(
  cell_id INTEGER NOT NULL REFERENCES cells(id) ON DELETE CASCADE, chunk_id INTEGER NOT NULL,
  triangles INTEGER NOT NULL, whole INTEGER NOT NULL,
  origin_x REAL, origin_y REAL, origin_z REAL, min_x REAL, min_y REAL, min_z REAL, max_x REAL, max_y REAL, max_z REAL,
  geometry BLOB,
  PRIMARY KEY(cell_id, chunk_id));
CREATE TABLE far_choice(
  cell_id INTEGER NOT NULL REFERENCES cells(id) ON DELETE CASCADE, face INTEGER NOT NULL,
  geometry_tiles INTEGER NOT NULL, tdm_triangles INTEGER NOT NULL, replaced_triangles INTEGER NOT NULL,
  geometry_triangles INTEGER NOT NULL,
  PRIMARY KEY(cell_id, face));
UPDATE cells SET far_geometry_triangles = 6 WHERE id = 7;
INSERT INTO far_geometry VALUES(7, 11, 6, 1, 0, 0, 0, 4, 4, 4, 5, 5, 5, x'');
PRAGMA user_version = 4;
)sql");
}

TEST(CellDbMigration, AVersionTwoDatabaseOpensReadOnlyAsItIs) {
  test::TempDir dir;
  write_v2_database(dir / "old.db");
  CellDb db(dir / "old.db", CellDb::Mode::read_only);
  EXPECT_EQ(db.schema_version(), 2);
  const auto cell = db.get_cell(7);
  ASSERT_TRUE(cell);
  ASSERT_EQ(cell->samples.size(), 1u);
  EXPECT_EQ(cell->samples[0].eye, (Vec3d{1, 1, 1}));
  EXPECT_EQ(cell->samples[0].parent, -1);
  EXPECT_EQ(cell->samples[0].void_after, -1);  // not measured in version 2
  EXPECT_EQ(cell->samples[0].removed_pixels, 0u);
  ASSERT_EQ(cell->samples[0].faces.size(), 1u);
  EXPECT_EQ(cell->samples[0].faces[0].mesh, (std::vector<std::uint8_t>{3, 4}));
}

TEST(CellDbMigration, OpeningReadWriteMigratesToTheCurrentVersionKeepingTheCells) {
  test::TempDir dir;
  write_v2_database(dir / "old.db");
  {
    CellDb db(dir / "old.db", CellDb::Mode::read_write);
    EXPECT_EQ(db.schema_version(), 5);
    EXPECT_TRUE(db.integrity_ok());
    // New rows carry the new columns.
    CellRow row = *db.get_cell(7);
    row.id = 8;
    row.samples[0].void_after = 0.004;
    row.samples[0].covered_pixels = 100;
    row.samples[0].removed_pixels = 90;
    row.samples[0].seconds = 1.5;
    FarGeometryRow far;
    far.chunk_id = 11;
    far.triangles = 2;
    far.origin = {1, 2, 3};
    far.bounds = {{0, 0, 0}, {1, 1, 1}};
    far.geometry = {5, 6, 7};
    row.far_geometry.push_back(far);
    row.far_geometry_triangles = 2;
    row.far_choice.push_back({2, 0x8001u, 10, 4, 2});
    db.put_cell(row);
  }
  CellDb db(dir / "old.db", CellDb::Mode::read_only);
  EXPECT_EQ(db.schema_version(), 5);
  const auto old_cell = db.get_cell(7), new_cell = db.get_cell(8);
  ASSERT_TRUE(old_cell && new_cell);
  EXPECT_EQ(old_cell->content_hash, "content");
  EXPECT_EQ(old_cell->samples[0].void_after, -1);
  EXPECT_EQ(new_cell->samples[0].void_after, 0.004);
  EXPECT_EQ(new_cell->samples[0].covered_pixels, 100u);
  EXPECT_TRUE(old_cell->far_geometry.empty());
  ASSERT_EQ(new_cell->far_geometry.size(), 1u);
  EXPECT_EQ(new_cell->far_geometry[0].chunk_id, 11);
  EXPECT_EQ(new_cell->far_geometry[0].origin, (Vec3d{1, 2, 3}));
  EXPECT_EQ(new_cell->far_geometry[0].geometry, (std::vector<std::uint8_t>{5, 6, 7}));
  EXPECT_EQ(new_cell->far_geometry_triangles, 2u);
  ASSERT_EQ(new_cell->far_choice.size(), 1u);
  EXPECT_EQ(new_cell->far_choice[0].geometry_tiles, 0x8001u);
  EXPECT_EQ(new_cell->far_choice[0].replaced_triangles, 4u);
  EXPECT_EQ(new_cell->samples[0].removed_pixels, 90u);
  EXPECT_EQ(new_cell->samples[0].seconds, 1.5);
}

TEST(CellDbMigration, AVersionFourDatabaseOpensReadOnlyWithItsFarRowsAtLevelZero) {
  test::TempDir dir;
  write_v4_database(dir / "v4.db");
  const CellDb db(dir / "v4.db", CellDb::Mode::read_only);
  EXPECT_EQ(db.schema_version(), 4);
  for (const bool blobs : {true, false}) {
    const auto cell = db.get_cell(7, blobs);
    ASSERT_TRUE(cell);
    ASSERT_EQ(cell->far_geometry.size(), 1u);
    EXPECT_EQ(cell->far_geometry[0].chunk_id, 11);
    EXPECT_EQ(cell->far_geometry[0].level, 0);
  }
  EXPECT_EQ(db.totals().far_geometry_triangles, 6u);
  EXPECT_EQ(db.totals().far_level_rows, 0u);
}

TEST(CellDbMigration, AVersionFourDatabaseMigratesItsFarRowsToLevelZeroAndStoresLevels) {
  test::TempDir dir;
  write_v4_database(dir / "v4.db");
  {
    CellDb db(dir / "v4.db", CellDb::Mode::read_write);
    EXPECT_EQ(db.schema_version(), 5);
    EXPECT_TRUE(db.integrity_ok());
    CellRow row = *db.get_cell(7);
    EXPECT_EQ(row.far_geometry.at(0).level, 0);
    row.id = 8;
    row.far_geometry.at(0).level = 3;
    row.far_geometry.at(0).triangles = 2;
    row.far_geometry_triangles = 2;
    db.put_cell(row);
  }
  const CellDb db(dir / "v4.db", CellDb::Mode::read_only);
  EXPECT_EQ(db.schema_version(), 5);
  EXPECT_EQ(db.get_cell(7)->far_geometry.at(0).level, 0);
  EXPECT_EQ(db.get_cell(8)->far_geometry.at(0).level, 3);
  EXPECT_EQ(db.get_cell(8, false)->far_geometry.at(0).level, 3);
  const CellDbTotals t = db.totals();
  EXPECT_EQ(t.far_level_rows, 1u);
  EXPECT_EQ(t.far_level_triangles, 2u);
  EXPECT_EQ(t.far_geometry_triangles, 8u);
}

TEST(CellDbMigration, MergeRefusesAShardOfVersionFourNamingIt) {
  test::TempDir dir;
  write_v4_database(dir / "shard.db");
  CellDb target(dir / "merged.db", CellDb::Mode::read_write);
  const CellDb shard(dir / "shard.db", CellDb::Mode::read_only);
  try {
    copy_cells(target, shard);
    FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("shard.db"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("schema version 4 differs"), std::string::npos) << e.what();
  }
}

TEST(CellDbMigration, MergingANewShardIntoAVersionFourDatabaseMigratesItFirst) {
  test::TempDir dir;
  write_v4_database(dir / "merged.db");
  CellRow cell;  // a done cell without samples whose far geometry is level 2 of chunk 11
  cell.id = 9;
  cell.status = "done";
  cell.input_hash = cell.cull_hash = "h";
  FarGeometryRow level;
  level.chunk_id = 11;
  level.level = 2;
  level.whole = true;
  level.triangles = 3;
  level.bounds = {{4, 4, 4}, {5, 5, 5}};
  cell.far_geometry = {level};
  cell.far_geometry_triangles = 3;
  cell.content_hash = cell_content_hash(cell);
  {
    CellDb shard(dir / "shard.db", CellDb::Mode::read_write);
    shard.put_cell(cell);
  }
  CellDb target(dir / "merged.db", CellDb::Mode::read_write);  // as merge opens it
  EXPECT_EQ(target.schema_version(), 5);
  const CellDb shard(dir / "shard.db", CellDb::Mode::read_only);
  EXPECT_EQ(copy_cells(target, shard).copied, 1u);
  EXPECT_EQ(target.get_cell(9)->far_geometry.at(0).level, 2);
  EXPECT_EQ(target.get_cell(7)->far_geometry.at(0).level, 0);
}

TEST(CellDbMigration, MergeRefusesAShardOfAnotherVersionNamingIt) {
  test::TempDir dir;
  write_v2_database(dir / "shard.db");
  CellDb target(dir / "merged.db", CellDb::Mode::read_write);
  const CellDb shard(dir / "shard.db", CellDb::Mode::read_only);
  try {
    copy_cells(target, shard);
    FAIL() << "expected a refusal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("shard.db"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("schema version 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellbake
