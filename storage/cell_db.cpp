#include "storage/cell_db.h"

#include <nlohmann/json.hpp>

#include <bit>
#include <chrono>
#include <thread>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "stages/hashing.h"
#include "storage/sqlite_db.h"

namespace cellbake {
namespace {

constexpr int kCellDbSchemaVersion = 5;
constexpr int kOldestReadableSchemaVersion = 2;  // read-only opens of v2 databases (one sample per cell) still work

// Migrations: entry i upgrades schema version i to i + 1.
const char* kMigrations[] = {
    R"sql(
CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE cells(
  id INTEGER PRIMARY KEY, region INTEGER NOT NULL, gx INTEGER NOT NULL, gy INTEGER NOT NULL, gz INTEGER NOT NULL,
  min_x REAL, min_y REAL, min_z REAL, max_x REAL, max_y REAL, max_z REAL,
  status TEXT NOT NULL, error TEXT NOT NULL DEFAULT '',
  input_hash TEXT NOT NULL, cull_hash TEXT NOT NULL, content_hash TEXT NOT NULL,
  cull_half_size REAL, near_triangles INTEGER, near_chunks BLOB,
  far_triangles INTEGER, bytes INTEGER, max_coverage_error REAL, max_depth_error REAL,
  stage_seconds TEXT NOT NULL DEFAULT '{}');
CREATE TABLE samples(
  cell_id INTEGER NOT NULL REFERENCES cells(id) ON DELETE CASCADE, sample_index INTEGER NOT NULL,
  eye_x REAL NOT NULL, eye_y REAL NOT NULL, eye_z REAL NOT NULL, parent INTEGER NOT NULL,
  PRIMARY KEY(cell_id, sample_index));
CREATE TABLE faces(
  cell_id INTEGER NOT NULL, sample_index INTEGER NOT NULL, face INTEGER NOT NULL,
  image_format TEXT NOT NULL, image BLOB NOT NULL, mesh BLOB NOT NULL,
  triangles INTEGER NOT NULL, coverage_error REAL, depth_error REAL,
  PRIMARY KEY(cell_id, sample_index, face),
  FOREIGN KEY(cell_id, sample_index) REFERENCES samples(cell_id, sample_index) ON DELETE CASCADE);
)sql",
    // v2: the simplifier reports outline movement in pixels, not coverage samples.
    R"sql(
ALTER TABLE cells RENAME COLUMN max_coverage_error TO max_boundary_error_px;
ALTER TABLE faces RENAME COLUMN coverage_error TO boundary_error_px;
)sql",
    // v3: several samples per cell (incremental textured depth meshes): the
    // void curve of the best-next-view search and the redundancy figures.
    R"sql(
ALTER TABLE samples ADD COLUMN void_after REAL NOT NULL DEFAULT -1;
ALTER TABLE samples ADD COLUMN covered_pixels INTEGER NOT NULL DEFAULT 0;
ALTER TABLE samples ADD COLUMN removed_pixels INTEGER NOT NULL DEFAULT 0;
ALTER TABLE samples ADD COLUMN seconds REAL NOT NULL DEFAULT 0;
)sql",
    // v4: the far field's representation chosen per face tile (exact far
    // geometry or textured depth meshes; issue #13).
    R"sql(
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
)sql",
    // v5: a far geometry row may draw a simplified level of its chunk from the
    // geometry store (issue #35); 0 = the chunk itself, as every older row.
    R"sql(
ALTER TABLE far_geometry ADD COLUMN level INTEGER NOT NULL DEFAULT 0;
)sql",
};

int user_version(SqliteDb& db) {
  SqliteStatement s(db, "PRAGMA user_version");
  s.step();
  return static_cast<int>(s.column_int(0));
}

// Throws unless the file opened read-write is empty (no tables: a new
// database) or one of ours: a geometry store, or any other SQLite file, is
// never adopted and migrated into a cell database.
void refuse_foreign_database(SqliteDb& db, const std::filesystem::path& path, int version) {
  const std::string refusal = path.string() + ": is not a cellbake cell database (";
  const std::string advice = "); refusing to write cells into it: choose another --out path";
  if (version == 0) {
    SqliteStatement tables(db, "SELECT count(*) FROM sqlite_master");
    tables.step();
    if (tables.column_int(0) != 0) {
      std::string kind = "an SQLite file with other tables";
      try {
        SqliteStatement s(db, "SELECT value FROM meta WHERE key = 'kind'");
        if (s.step()) {
          // Ours, created by another process between reading the version
          // and listing the tables.
          if (s.column_text(0) == "cellbake-cell-database") return;
          kind = "its kind is '" + s.column_text(0) + "'";
        }
      } catch (const std::exception&) {
      }
      throw std::runtime_error(refusal + kind + advice);
    }
    return;
  }
  std::string kind;
  try {
    SqliteStatement s(db, "SELECT value FROM meta WHERE key = 'kind'");
    if (s.step()) kind = s.column_text(0);
  } catch (const std::exception&) {
    kind = "";
  }
  // A bake writes `kind` right after creating the schema; a database killed
  // in between has the schema and no kind yet, which is ours too.
  if (!kind.empty() && kind != "cellbake-cell-database")
    throw std::runtime_error(refusal + "its kind is '" + kind + "'" + advice);
}

}  // namespace

std::vector<std::uint8_t> pack_near_chunks(const std::vector<NearChunkRow>& rows) {
  std::vector<std::uint8_t> out(rows.size() * 13);
  std::uint8_t* p = out.data();
  for (const auto& r : rows) {
    std::memcpy(p, &r.chunk_id, 8);
    std::memcpy(p + 8, &r.triangles, 4);
    p[12] = r.whole ? 1 : 0;
    p += 13;
  }
  return out;
}

std::vector<NearChunkRow> unpack_near_chunks(const std::uint8_t* data, std::size_t size) {
  if (size % 13 != 0) throw std::runtime_error("near-chunk list: length " + std::to_string(size) + " is not 13*n");
  std::vector<NearChunkRow> rows(size / 13);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::uint8_t* p = data + 13 * i;
    std::memcpy(&rows[i].chunk_id, p, 8);
    std::memcpy(&rows[i].triangles, p + 8, 4);
    if (p[12] > 1) throw std::runtime_error("near-chunk list: bad flag");
    rows[i].whole = p[12] == 1;
  }
  return rows;
}

CellDb::CellDb(const std::filesystem::path& path, Mode mode) {
  if (mode == Mode::read_only && !std::filesystem::exists(path))
    throw std::runtime_error(path.string() + ": cell database does not exist");
  if (mode == Mode::read_write) {
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
      throw std::runtime_error(path.string() +
                               ": is not a regular file (a directory, device or pipe); refusing to write a cell "
                               "database there");
  }
  db_ = std::make_unique<SqliteDb>(
      path, mode == Mode::read_only ? SqliteDb::Mode::read_only : SqliteDb::Mode::read_write_create);
  db_->exec("PRAGMA foreign_keys=ON");
  if (mode == Mode::read_only) {
    schema_version_ = user_version(*db_);
    if (schema_version_ < kOldestReadableSchemaVersion || schema_version_ > kCellDbSchemaVersion)
      throw std::runtime_error(path.string() + ": not a cellbake cell database of schema version " +
                               std::to_string(kOldestReadableSchemaVersion) + " to " +
                               std::to_string(kCellDbSchemaVersion));
    return;
  }
  refuse_foreign_database(*db_, path, user_version(*db_));
  // Switching to WAL needs the file to itself and SQLite does not wait for it
  // (no busy handler): retry while another process opens it at the same moment.
  for (int attempt = 0;; ++attempt) {
    try {
      db_->exec("PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;");
      break;
    } catch (const std::runtime_error& e) {
      if (attempt >= 600 || std::string(e.what()).find("database is locked") == std::string::npos) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  // Schema creation and migrations in one write transaction, the version read
  // inside it: of two processes opening a new file at once, the second waits
  // and then finds the schema made (never "table cells already exists").
  SqliteTransaction tx(*db_);
  int version = user_version(*db_);
  refuse_foreign_database(*db_, path, version);
  if (version > kCellDbSchemaVersion)
    throw std::runtime_error(path.string() + ": cell database schema version " + std::to_string(version) +
                             " is newer than this cellbake (" + std::to_string(kCellDbSchemaVersion) + ")");
  for (; version < kCellDbSchemaVersion; ++version) db_->exec(kMigrations[version]);
  db_->exec("PRAGMA user_version=" + std::to_string(version));
  schema_version_ = version;
  set_meta("kind", "cellbake-cell-database");
  tx.commit();
}

CellDb::~CellDb() = default;

const std::filesystem::path& CellDb::path() const { return db_->file(); }
std::string CellDb::attach_uri() const { return db_->attach_uri(); }

void CellDb::set_meta(const std::string& key, const std::string& value) {
  SqliteStatement s(*db_, "INSERT INTO meta VALUES(?,?) ON CONFLICT(key) DO UPDATE SET value=excluded.value");
  s.bind(1, key).bind(2, value).run();
}

std::optional<std::string> CellDb::meta(const std::string& key) const {
  SqliteStatement s(*db_, "SELECT value FROM meta WHERE key=?");
  s.bind(1, key);
  if (!s.step()) return std::nullopt;
  return s.column_text(0);
}

void CellDb::put_cell(const CellRow& c) {
  SqliteTransaction tx(*db_);
  {
    SqliteStatement del(*db_, "DELETE FROM cells WHERE id=?");
    del.bind(1, c.id).run();
  }
  {
    SqliteStatement s(*db_,
                      "INSERT INTO cells(id, region, gx, gy, gz, min_x, min_y, min_z, max_x, max_y, max_z, status, "
                      "error, input_hash, cull_hash, content_hash, cull_half_size, near_triangles, near_chunks, "
                      "far_triangles, bytes, max_boundary_error_px, max_depth_error, stage_seconds, "
                      "far_geometry_triangles) VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
    const auto near = pack_near_chunks(c.near_chunks);
    nlohmann::json secs(c.stage_seconds);
    s.bind(1, c.id).bind(2, std::int64_t(c.region)).bind(3, std::int64_t(c.gx)).bind(4, std::int64_t(c.gy));
    s.bind(5, std::int64_t(c.gz)).bind(6, c.bounds.lo.x).bind(7, c.bounds.lo.y).bind(8, c.bounds.lo.z);
    s.bind(9, c.bounds.hi.x).bind(10, c.bounds.hi.y).bind(11, c.bounds.hi.z).bind(12, c.status).bind(13, c.error);
    s.bind(14, c.input_hash).bind(15, c.cull_hash).bind(16, c.content_hash).bind(17, c.cull_half_size);
    s.bind(18, std::int64_t(c.near_triangles)).bind_blob(19, near.data(), near.size());
    s.bind(20, std::int64_t(c.far_triangles)).bind(21, std::int64_t(c.bytes)).bind(22, c.max_boundary_error_px);
    s.bind(23, c.max_depth_error).bind(24, secs.dump()).bind(25, std::int64_t(c.far_geometry_triangles));
    s.run();
  }
  SqliteStatement ins_geometry(*db_, "INSERT INTO far_geometry VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  for (const FarGeometryRow& g : c.far_geometry) {
    ins_geometry.bind(1, c.id).bind(2, g.chunk_id).bind(3, std::int64_t(g.triangles)).bind(4, std::int64_t(g.whole));
    ins_geometry.bind(5, g.origin.x).bind(6, g.origin.y).bind(7, g.origin.z).bind(8, g.bounds.lo.x);
    ins_geometry.bind(9, g.bounds.lo.y).bind(10, g.bounds.lo.z).bind(11, g.bounds.hi.x).bind(12, g.bounds.hi.y);
    ins_geometry.bind(13, g.bounds.hi.z).bind_blob(14, g.geometry.data(), g.geometry.size());
    ins_geometry.bind(15, std::int64_t(g.level)).run();
  }
  SqliteStatement ins_choice(*db_, "INSERT INTO far_choice VALUES(?,?,?,?,?,?)");
  for (const FarChoiceRow& f : c.far_choice) {
    ins_choice.bind(1, c.id).bind(2, std::int64_t(f.face)).bind(3, std::int64_t(f.geometry_tiles));
    ins_choice.bind(4, std::int64_t(f.tdm_triangles)).bind(5, std::int64_t(f.replaced_triangles));
    ins_choice.bind(6, std::int64_t(f.geometry_triangles)).run();
  }
  SqliteStatement ins_sample(*db_, "INSERT INTO samples VALUES(?,?,?,?,?,?,?,?,?,?)");
  SqliteStatement ins_face(*db_, "INSERT INTO faces VALUES(?,?,?,?,?,?,?,?,?)");
  for (const auto& sm : c.samples) {
    ins_sample.bind(1, c.id).bind(2, std::int64_t(sm.index)).bind(3, sm.eye.x).bind(4, sm.eye.y).bind(5, sm.eye.z);
    ins_sample.bind(6, std::int64_t(sm.parent)).bind(7, sm.void_after).bind(8, std::int64_t(sm.covered_pixels));
    ins_sample.bind(9, std::int64_t(sm.removed_pixels)).bind(10, sm.seconds).run();
    for (const auto& f : sm.faces) {
      ins_face.bind(1, c.id).bind(2, std::int64_t(sm.index)).bind(3, std::int64_t(f.face)).bind(4, f.image_format);
      ins_face.bind_blob(5, f.image.data(), f.image.size()).bind_blob(6, f.mesh.data(), f.mesh.size());
      ins_face.bind(7, std::int64_t(f.triangles)).bind(8, f.boundary_error_px).bind(9, f.depth_error).run();
    }
  }
  tx.commit();
}

std::map<std::int64_t, CellStamp> CellDb::stamps() const {
  std::map<std::int64_t, CellStamp> out;
  SqliteStatement s(*db_,
                    "SELECT id, status, input_hash, cull_hash, content_hash, cull_half_size, near_chunks, "
                    "near_triangles FROM cells");
  while (s.step()) {
    CellStamp st;
    st.id = s.column_int(0);
    st.status = s.column_text(1);
    st.input_hash = s.column_text(2);
    st.cull_hash = s.column_text(3);
    st.content_hash = s.column_text(4);
    st.cull_half_size = s.column_double(5);
    std::size_t n = 0;
    const std::uint8_t* p = s.column_blob_data(6, n);
    try {
      if (p) st.near_chunks = unpack_near_chunks(p, n);
    } catch (const std::exception& e) {
      st.error = path().string() + ": cell " + std::to_string(st.id) + ": near_chunks: " + e.what();
    }
    st.near_triangles = static_cast<std::uint64_t>(s.column_int(7));
    out[st.id] = std::move(st);
  }
  return out;
}

std::vector<std::int64_t> CellDb::cell_ids() const {
  std::vector<std::int64_t> ids;
  SqliteStatement s(*db_, "SELECT id FROM cells ORDER BY id");
  while (s.step()) ids.push_back(s.column_int(0));
  return ids;
}

std::optional<CellRow> CellDb::get_cell(std::int64_t id, bool with_blobs) const {
  SqliteStatement s(*db_,
                    std::string("SELECT region, gx, gy, gz, min_x, min_y, min_z, max_x, max_y, max_z, status, error, input_hash, "
                    "cull_hash, content_hash, cull_half_size, near_triangles, near_chunks, far_triangles, bytes, "
                    "max_boundary_error_px, max_depth_error, stage_seconds, ") +
                        std::string(schema_version_ >= 4 ? "far_geometry_triangles" : "0") +
                        " FROM cells WHERE id=?");
  s.bind(1, id);
  if (!s.step()) return std::nullopt;
  CellRow c;
  c.id = id;
  c.region = int(s.column_int(0));
  c.gx = int(s.column_int(1));
  c.gy = int(s.column_int(2));
  c.gz = int(s.column_int(3));
  c.bounds = {{s.column_double(4), s.column_double(5), s.column_double(6)},
              {s.column_double(7), s.column_double(8), s.column_double(9)}};
  c.status = s.column_text(10);
  c.error = s.column_text(11);
  c.input_hash = s.column_text(12);
  c.cull_hash = s.column_text(13);
  c.content_hash = s.column_text(14);
  c.cull_half_size = s.column_double(15);
  c.near_triangles = std::uint64_t(s.column_int(16));
  std::size_t n = 0;
  const std::uint8_t* p = s.column_blob_data(17, n);
  try {
    if (p) c.near_chunks = unpack_near_chunks(p, n);
  } catch (const std::exception& e) {
    throw std::runtime_error(path().string() + ": cell " + std::to_string(id) + ": near_chunks: " + e.what());
  }
  c.far_triangles = std::uint64_t(s.column_int(18));
  c.bytes = std::uint64_t(s.column_int(19));
  c.max_boundary_error_px = s.column_double(20);
  c.max_depth_error = s.column_double(21);
  auto secs = nlohmann::json::parse(s.column_text(22), nullptr, false);
  if (secs.is_object())
    for (auto& [k, v] : secs.items())
      if (v.is_number()) c.stage_seconds[k] = v.get<double>();
  c.far_geometry_triangles = std::uint64_t(s.column_int(23));
  if (schema_version_ >= 4) {
    SqliteStatement fg(*db_, std::string("SELECT chunk_id, triangles, whole, origin_x, origin_y, origin_z, min_x, "
                                         "min_y, min_z, max_x, max_y, max_z, ") +
                                 (with_blobs ? "geometry" : "x''") +
                                 (schema_version_ >= 5 ? ", level" : ", 0") +
                                 " FROM far_geometry WHERE cell_id=? ORDER BY chunk_id");
    fg.bind(1, id);
    while (fg.step()) {
      FarGeometryRow g;
      g.chunk_id = fg.column_int(0);
      g.triangles = std::uint32_t(fg.column_int(1));
      g.whole = fg.column_int(2) != 0;
      g.origin = {fg.column_double(3), fg.column_double(4), fg.column_double(5)};
      g.bounds = {{fg.column_double(6), fg.column_double(7), fg.column_double(8)},
                  {fg.column_double(9), fg.column_double(10), fg.column_double(11)}};
      g.geometry = fg.column_blob(12);
      const std::int64_t level = fg.column_int(13);
      // Out of int's range is damage as a negative level is: check_cell and
      // decode_cell refuse it by the value kept here.
      g.level = level < std::numeric_limits<int>::min() || level > std::numeric_limits<int>::max()
                    ? -1
                    : int(level);
      c.far_geometry.push_back(std::move(g));
    }
    SqliteStatement fc(*db_,
                       "SELECT face, geometry_tiles, tdm_triangles, replaced_triangles, geometry_triangles FROM "
                       "far_choice WHERE cell_id=? ORDER BY face");
    fc.bind(1, id);
    while (fc.step())
      c.far_choice.push_back({int(fc.column_int(0)), std::uint32_t(fc.column_int(1)),
                              std::uint64_t(fc.column_int(2)), std::uint64_t(fc.column_int(3)),
                              std::uint64_t(fc.column_int(4))});
  }

  SqliteStatement ss(*db_, schema_version_ >= 3
                               ? "SELECT sample_index, eye_x, eye_y, eye_z, parent, void_after, covered_pixels, "
                                 "removed_pixels, seconds FROM samples WHERE cell_id=? ORDER BY sample_index"
                               : "SELECT sample_index, eye_x, eye_y, eye_z, parent, -1, 0, 0, 0 FROM samples "
                                 "WHERE cell_id=? ORDER BY sample_index");
  ss.bind(1, id);
  while (ss.step()) {
    SampleRow sm;
    sm.index = int(ss.column_int(0));
    sm.eye = {ss.column_double(1), ss.column_double(2), ss.column_double(3)};
    sm.parent = int(ss.column_int(4));
    sm.void_after = ss.column_double(5);
    sm.covered_pixels = std::uint64_t(ss.column_int(6));
    sm.removed_pixels = std::uint64_t(ss.column_int(7));
    sm.seconds = ss.column_double(8);
    c.samples.push_back(std::move(sm));
  }
  SqliteStatement fs(*db_,
                     std::string("SELECT sample_index, face, image_format, ") +
                         (with_blobs ? "image, mesh" : "x'', x''") +
                         ", triangles, boundary_error_px, depth_error FROM faces WHERE cell_id=? ORDER BY sample_index, face");
  fs.bind(1, id);
  while (fs.step()) {
    const int si = int(fs.column_int(0));
    FaceRow f;
    f.face = int(fs.column_int(1));
    f.image_format = fs.column_text(2);
    f.image = fs.column_blob(3);
    f.mesh = fs.column_blob(4);
    f.triangles = std::uint32_t(fs.column_int(5));
    f.boundary_error_px = fs.column_double(6);
    f.depth_error = fs.column_double(7);
    for (auto& sm : c.samples)
      if (sm.index == si) sm.faces.push_back(std::move(f));
  }
  return c;
}

CellDbBytes CellDb::bytes_by_kind() const {
  CellDbBytes b;
  SqliteStatement cells(*db_, "SELECT count(*), total(length(near_chunks)) FROM cells WHERE status = 'done'");
  if (cells.step()) b.cells = std::uint64_t(cells.column_int(0)), b.near_list = std::uint64_t(cells.column_double(1));
  SqliteStatement faces(*db_,
                        "SELECT total(length(image)), total(length(mesh)) FROM faces "
                        "WHERE cell_id IN (SELECT id FROM cells WHERE status = 'done')");
  if (faces.step()) b.colour = std::uint64_t(faces.column_double(0)), b.mesh = std::uint64_t(faces.column_double(1));
  if (schema_version_ >= 4) {
    SqliteStatement far(*db_,
                        "SELECT total(length(geometry)) FROM far_geometry "
                        "WHERE cell_id IN (SELECT id FROM cells WHERE status = 'done')");
    if (far.step()) b.far_geometry = std::uint64_t(far.column_double(0));
  }
  return b;
}

CellDbTotals CellDb::totals() const {
  CellDbTotals t;
  Hasher h;
  SqliteStatement s(*db_,
                    "SELECT id, status, content_hash, bytes, far_triangles, near_triangles, stage_seconds FROM cells "
                    "ORDER BY id");
  while (s.step()) {
    if (s.column_text(1) == "done") {
      ++t.cells_done;
      h.u64(std::uint64_t(s.column_int(0))).text(s.column_text(2));
      t.bytes += std::uint64_t(s.column_int(3));
      t.far_triangles += std::uint64_t(s.column_int(4));
      t.near_triangles += std::uint64_t(s.column_int(5));
    } else {
      ++t.cells_failed;
    }
    auto secs = nlohmann::json::parse(s.column_text(6), nullptr, false);
    if (secs.is_object())
      for (auto& [k, v] : secs.items())
        if (v.is_number()) t.stage_seconds[k] += v.get<double>();
  }
  t.content_hash = h.hex();
  if (schema_version_ >= 4) {
    SqliteStatement cells(*db_, "SELECT total(far_geometry_triangles) FROM cells WHERE status = 'done'");
    if (cells.step()) t.far_geometry_triangles = std::uint64_t(cells.column_double(0));
    SqliteStatement choice(*db_,
                           "SELECT geometry_tiles, replaced_triangles FROM far_choice "
                           "WHERE cell_id IN (SELECT id FROM cells WHERE status = 'done')");
    while (choice.step()) {
      t.geometry_tiles += std::uint64_t(std::popcount(std::uint32_t(choice.column_int(0))));
      t.face_tiles += 16;
      t.replaced_triangles += std::uint64_t(choice.column_int(1));
    }
  }
  if (schema_version_ >= 5) {
    SqliteStatement levels(*db_,
                           "SELECT count(*), total(triangles) FROM far_geometry WHERE level != 0 AND "
                           "cell_id IN (SELECT id FROM cells WHERE status = 'done')");
    if (levels.step()) {
      t.far_level_rows = std::uint64_t(levels.column_int(0));
      t.far_level_triangles = std::uint64_t(levels.column_double(1));
    }
  }
  SqliteStatement samples(*db_, schema_version_ >= 3
                                    ? "SELECT count(*), total(CASE WHEN parent >= 0 THEN covered_pixels END), "
                                      "total(CASE WHEN parent >= 0 THEN removed_pixels END) FROM samples"
                                    : "SELECT count(*), 0, 0 FROM samples");
  if (samples.step()) {
    t.samples = std::uint64_t(samples.column_int(0));
    t.delta_covered_pixels = std::uint64_t(samples.column_double(1));
    t.delta_removed_pixels = std::uint64_t(samples.column_double(2));
  }
  return t;
}

bool CellDb::integrity_ok() const {
  SqliteStatement s(*db_, "PRAGMA integrity_check");
  return s.step() && s.column_text(0) == "ok";
}

}  // namespace cellbake
