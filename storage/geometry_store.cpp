#include "storage/geometry_store.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "stages/encode/encode.h"
#include "stages/hashing.h"
#include "storage/chunk_codec.h"
#include "storage/output_file.h"
#include "storage/sqlite_db.h"

namespace cellbake {
namespace {

// 2: materials carry texture_id and alpha_test, textures live in `textures`,
// chunk blobs may carry normals. Version 1 stores are still read (no textures).
constexpr int kStoreSchemaVersion = 2;
constexpr std::size_t kChunksPerTransaction = 256;

const char* kSchema = R"sql(
CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE sources(id INTEGER PRIMARY KEY, path TEXT NOT NULL, bytes INTEGER NOT NULL,
                     hash TEXT NOT NULL, triangles INTEGER NOT NULL);
CREATE TABLE materials(id INTEGER PRIMARY KEY, name TEXT NOT NULL, r INTEGER, g INTEGER, b INTEGER, a INTEGER,
                       texture TEXT NOT NULL, texture_id INTEGER NOT NULL, alpha_test INTEGER NOT NULL);
CREATE TABLE textures(id INTEGER PRIMARY KEY, source TEXT NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL,
                      wrap_u INTEGER NOT NULL, wrap_v INTEGER NOT NULL, has_alpha INTEGER NOT NULL,
                      image BLOB NOT NULL);
CREATE TABLE chunks(id INTEGER PRIMARY KEY,
                    origin_x REAL NOT NULL, origin_y REAL NOT NULL, origin_z REAL NOT NULL,
                    min_x REAL NOT NULL, min_y REAL NOT NULL, min_z REAL NOT NULL,
                    max_x REAL NOT NULL, max_y REAL NOT NULL, max_z REAL NOT NULL,
                    triangle_count INTEGER NOT NULL, vertex_count INTEGER NOT NULL,
                    geometry BLOB NOT NULL);
CREATE VIRTUAL TABLE chunk_rtree USING rtree(id, min_x, max_x, min_y, max_y, min_z, max_z);
CREATE TABLE chunk_lods(chunk_id INTEGER NOT NULL, level INTEGER NOT NULL, error REAL NOT NULL,
                        triangle_count INTEGER NOT NULL, vertex_count INTEGER NOT NULL, geometry BLOB NOT NULL,
                        PRIMARY KEY(chunk_id, level));
)sql";

// True when `path` is a finished geometry store of ours (any schema).
bool is_geometry_store(const std::filesystem::path& path) {
  try {
    SqliteDb db(path, SqliteDb::Mode::read_only);
    SqliteStatement s(db, "SELECT value FROM meta WHERE key = 'kind'");
    return s.step() && s.column_text(0) == "cellbake-geometry-store";
  } catch (const std::exception&) {
    return false;
  }
}

// Refuses to let a new store replace anything but an absent path, an empty
// file or an existing geometry store: a device node, a directory, a pipe, a
// symbolic link, a cell database or any other file stays as it is.
void check_store_target(const std::filesystem::path& path) {
  refuse_non_regular_target(path, "a geometry store");
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return;
  const std::string where = path.string() + ": ";
  if (std::filesystem::file_size(path, ec) == 0 && !ec) return;
  if (!is_geometry_store(path))
    throw std::runtime_error(where + "exists and is not a cellbake geometry store (a cell database? another file?); "
                                     "refusing to replace it: remove it or choose another --store path");
}

// Removes `STORE.tmp-PID` and `STORE.spill-PID` files next to `store` left by
// ingests that were killed: the process PID is gone from this machine and the
// file has not been written for 10 minutes (a live ingest on another machine
// sharing the folder keeps writing it).
void remove_stale_temporaries(const std::filesystem::path& store) {
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::absolute(store, ec).parent_path();
  if (ec) return;
  const std::string name = store.filename().string();
  const auto now = std::filesystem::file_time_type::clock::now();
  std::vector<std::filesystem::path> stale;  // collected first: no removal while the folder is listed
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string file = entry.path().filename().string();
    std::string rest;
    for (const char* suffix : {".tmp-", ".spill-"})
      if (file.rfind(name + suffix, 0) == 0) rest = file.substr(name.size() + std::strlen(suffix));
    if (rest.empty() || rest.size() > 9 || rest.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(rest));
    if (pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code time_ec;
    const auto written = std::filesystem::last_write_time(entry.path(), time_ec);
    if (time_ec || now - written < std::chrono::minutes(10)) continue;
    stale.push_back(entry.path());
  }
  for (const auto& path : stale) {
    std::error_code remove_ec;
    std::filesystem::remove(path, remove_ec);
  }
}

// The rows of each kind as the content hash sees them (GeometryStoreWriter
// while writing, stored_content_hash from the file): values as bound, in id order.
void hash_texture(Hasher& h, std::int64_t id, std::int64_t width, std::int64_t height, std::int64_t wrap_u,
                  std::int64_t wrap_v, std::int64_t has_alpha, const std::vector<Rgba8>& top_down) {
  h.u64(std::uint64_t(id)).u64(std::uint64_t(width)).u64(std::uint64_t(height));
  h.u64(std::uint64_t(wrap_u)).u64(std::uint64_t(wrap_v)).u64(std::uint64_t(has_alpha));
  h.bytes(top_down.data(), top_down.size() * sizeof(Rgba8));  // texels, not PNG bytes: a libpng update changes nothing
}
void hash_material(Hasher& h, std::int64_t index, const std::string& name, const std::int64_t (&rgba)[4],
                   const std::string& texture, std::int64_t texture_id, std::int64_t alpha_test) {
  h.u64(std::uint64_t(index)).text(name);
  for (std::int64_t c : rgba) h.u64(std::uint64_t(c));
  h.text(texture).u64(std::uint64_t(texture_id)).u64(std::uint64_t(alpha_test));
}
void hash_chunk(Hasher& h, std::int64_t id, const double (&origin_and_bounds)[9], std::int64_t triangles,
                std::int64_t vertices, const void* blob, std::size_t size) {
  h.u64(std::uint64_t(id));
  for (double v : origin_and_bounds) h.f64(v);
  h.u64(std::uint64_t(triangles)).u64(std::uint64_t(vertices)).bytes(blob, size).u64(size);
}
void hash_chunk_lod(Hasher& h, std::int64_t id, std::int64_t level, double error, std::int64_t triangles,
                    std::int64_t vertices, const void* blob, std::size_t size) {
  h.u64(std::uint64_t(id)).u64(std::uint64_t(level)).f64(error);
  h.u64(std::uint64_t(triangles)).u64(std::uint64_t(vertices)).bytes(blob, size).u64(size);
}
// The chunk levels count only when there are some, so stores without levels
// keep the hash they had before levels existed.
std::string combine_content_hash(const Hasher& textures, const Hasher& materials, const Hasher& chunks,
                                 const Hasher& lods, std::uint64_t lod_rows) {
  Hasher h;
  h.text("cellbake-store-content-v1").text(textures.hex()).text(materials.hex()).text(chunks.hex());
  if (lod_rows > 0) h.text("chunk-levels").text(lods.hex());
  return h.hex();
}

std::string fmt_double(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

// ---------------------------------------------------------------- writer

GeometryStoreWriter::GeometryStoreWriter(const std::filesystem::path& final_path)
    : final_path_(final_path),
      temp_path_(final_path.string() + ".tmp-" + std::to_string(::getpid())),
      textures_hash_(std::make_unique<Hasher>()),
      materials_hash_(std::make_unique<Hasher>()),
      chunks_hash_(std::make_unique<Hasher>()),
      lods_hash_(std::make_unique<Hasher>()) {
  check_store_target(final_path);
  remove_stale_temporaries(final_path);
  std::error_code ec;
  std::filesystem::remove(temp_path_, ec);
  db_ = std::make_unique<SqliteDb>(temp_path_, SqliteDb::Mode::read_write_create);
  db_->exec("PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF; PRAGMA page_size=16384;");
  db_->exec(kSchema);
  insert_chunk_ = std::make_unique<SqliteStatement>(
      *db_, "INSERT INTO chunks VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?)");
  insert_rtree_ = std::make_unique<SqliteStatement>(*db_, "INSERT INTO chunk_rtree VALUES(?,?,?,?,?,?,?)");
  insert_lod_ = std::make_unique<SqliteStatement>(*db_, "INSERT INTO chunk_lods VALUES(?,?,?,?,?,?)");
  db_->exec("BEGIN");
}

GeometryStoreWriter::~GeometryStoreWriter() {
  if (finished_) return;
  insert_chunk_.reset();
  insert_rtree_.reset();
  insert_lod_.reset();
  db_.reset();
  std::error_code ec;
  std::filesystem::remove(temp_path_, ec);
}

void GeometryStoreWriter::add_material(std::uint32_t index, const Material& m) {
  SqliteStatement s(*db_, "INSERT INTO materials VALUES(?,?,?,?,?,?,?,?,?)");
  s.bind(1, std::int64_t(index)).bind(2, m.name).bind(3, std::int64_t(m.color.r)).bind(4, std::int64_t(m.color.g));
  s.bind(5, std::int64_t(m.color.b)).bind(6, std::int64_t(m.color.a)).bind(7, m.texture);
  s.bind(8, m.texture_id).bind(9, std::int64_t(m.alpha_test ? 1 : 0));
  s.run();
  ++material_rows_;
  hash_material(*materials_hash_, std::int64_t(index), m.name, {m.color.r, m.color.g, m.color.b, m.color.a}, m.texture,
                m.texture_id, m.alpha_test ? 1 : 0);
}

std::int64_t GeometryStoreWriter::add_texture(const TextureImage& image, const std::string& source) {
  if (image.width <= 0 || image.height <= 0 ||
      image.texels.size() != std::size_t(image.width) * std::size_t(image.height))
    throw std::invalid_argument("add_texture: texels do not match the size of " + source);
  // Stored as PNG, top row first like any image file (the texels are bottom row first).
  std::vector<Rgba8> top_down(image.texels.size());
  for (int y = 0; y < image.height; ++y)
    std::copy_n(image.texels.begin() + std::ptrdiff_t(image.height - 1 - y) * image.width, image.width,
                top_down.begin() + std::ptrdiff_t(y) * image.width);
  ImageEncodeParams png;
  png.format = "png";
  const std::vector<std::uint8_t> blob = encode_image(top_down, image.width, image.height, png);
  const std::int64_t id = next_texture_id_++;
  SqliteStatement s(*db_, "INSERT INTO textures VALUES(?,?,?,?,?,?,?,?)");
  s.bind(1, id).bind(2, source).bind(3, std::int64_t(image.width)).bind(4, std::int64_t(image.height));
  s.bind(5, std::int64_t(image.wrap_u)).bind(6, std::int64_t(image.wrap_v)).bind(7, std::int64_t(image.has_alpha));
  s.bind_blob(8, blob.data(), blob.size());
  s.run();
  hash_texture(*textures_hash_, id, image.width, image.height, std::int64_t(image.wrap_u), std::int64_t(image.wrap_v),
               std::int64_t(image.has_alpha), top_down);
  return id;
}

void GeometryStoreWriter::add_source(const SourceFileRecord& src) {
  SqliteStatement s(*db_, "INSERT INTO sources(path, bytes, hash, triangles) VALUES(?,?,?,?)");
  s.bind(1, src.path).bind(2, std::int64_t(src.bytes)).bind(3, src.hash).bind(4, std::int64_t(src.triangles));
  s.run();
}

std::int64_t GeometryStoreWriter::add_chunk(const Chunk& chunk) {
  const std::int64_t id = next_id_++;
  const std::vector<std::uint8_t> blob = encode_chunk_blob(chunk);
  auto& s = *insert_chunk_;
  s.bind(1, id);
  s.bind(2, chunk.origin.x).bind(3, chunk.origin.y).bind(4, chunk.origin.z);
  s.bind(5, chunk.bounds.lo.x).bind(6, chunk.bounds.lo.y).bind(7, chunk.bounds.lo.z);
  s.bind(8, chunk.bounds.hi.x).bind(9, chunk.bounds.hi.y).bind(10, chunk.bounds.hi.z);
  s.bind(11, std::int64_t(chunk.triangle_count())).bind(12, std::int64_t(chunk.positions.size()));
  s.bind_blob(13, blob.data(), blob.size());
  s.run();
  hash_chunk(*chunks_hash_, id,
             {chunk.origin.x, chunk.origin.y, chunk.origin.z, chunk.bounds.lo.x, chunk.bounds.lo.y, chunk.bounds.lo.z,
              chunk.bounds.hi.x, chunk.bounds.hi.y, chunk.bounds.hi.z},
             std::int64_t(chunk.triangle_count()), std::int64_t(chunk.positions.size()), blob.data(), blob.size());
  // SQLite's R*Tree stores float32 and rounds outward, so its boxes stay conservative.
  auto& r = *insert_rtree_;
  r.bind(1, id);
  r.bind(2, chunk.bounds.lo.x).bind(3, chunk.bounds.hi.x);
  r.bind(4, chunk.bounds.lo.y).bind(5, chunk.bounds.hi.y);
  r.bind(6, chunk.bounds.lo.z).bind(7, chunk.bounds.hi.z);
  r.run();
  if (++pending_ >= kChunksPerTransaction) {
    db_->exec("COMMIT; BEGIN");
    pending_ = 0;
  }
  return id;
}

void GeometryStoreWriter::add_chunk_lods(std::int64_t id, const std::vector<ChunkLod>& lods) {
  if (id <= 0 || id >= next_id_) throw std::invalid_argument("add_chunk_lods: chunk " + std::to_string(id) + " was not added");
  for (const ChunkLod& l : lods) {
    const std::vector<std::uint8_t> blob = encode_chunk_blob(l.chunk);
    auto& s = *insert_lod_;
    s.bind(1, id).bind(2, std::int64_t(l.ref.level)).bind(3, l.ref.error);
    s.bind(4, std::int64_t(l.chunk.triangle_count())).bind(5, std::int64_t(l.chunk.positions.size()));
    s.bind_blob(6, blob.data(), blob.size());
    s.run();
    hash_chunk_lod(*lods_hash_, id, l.ref.level, l.ref.error, std::int64_t(l.chunk.triangle_count()),
                   std::int64_t(l.chunk.positions.size()), blob.data(), blob.size());
    ++lod_rows_;
  }
}

std::string GeometryStoreWriter::content_hash() const {
  return combine_content_hash(*textures_hash_, *materials_hash_, *chunks_hash_, *lods_hash_, lod_rows_);
}

void GeometryStoreWriter::finish(const StoreSummary& sum) {
  SqliteStatement s(*db_, "INSERT INTO meta VALUES(?,?)");
  auto put = [&](const std::string& k, const std::string& v) { s.bind(1, k).bind(2, v).run(); };
  put("schema_version", std::to_string(kStoreSchemaVersion));
  put("kind", "cellbake-geometry-store");
  put("bounds", fmt_double(sum.bounds.lo.x) + " " + fmt_double(sum.bounds.lo.y) + " " + fmt_double(sum.bounds.lo.z) +
                    " " + fmt_double(sum.bounds.hi.x) + " " + fmt_double(sum.bounds.hi.y) + " " +
                    fmt_double(sum.bounds.hi.z));
  put("triangles", std::to_string(sum.triangles));
  put("vertices", std::to_string(sum.vertices));
  put("chunks", std::to_string(sum.chunks));
  put("skipped_degenerate", std::to_string(sum.skipped_degenerate));
  put("skipped_duplicate", std::to_string(sum.skipped_duplicate));
  put("units", sum.units);
  put("content_hash", sum.content_hash);
  const std::uint64_t chunk_rows = std::uint64_t(next_id_ - 1), texture_rows = std::uint64_t(next_texture_id_ - 1);
  put("rows", "chunks=" + std::to_string(chunk_rows) + " chunk_rtree=" + std::to_string(chunk_rows) +
                  " materials=" + std::to_string(material_rows_) + " textures=" + std::to_string(texture_rows) +
                  " chunk_lods=" + std::to_string(lod_rows_));
  if (!sum.up.empty()) put("up", sum.up);
  if (!sum.up.empty() && !sum.up_source.empty()) put("up_source", sum.up_source);
  db_->exec("COMMIT");
  insert_chunk_.reset();
  insert_rtree_.reset();
  insert_lod_.reset();
  db_->exec("PRAGMA journal_mode=DELETE");
  db_.reset();
  std::filesystem::rename(temp_path_, final_path_);
  finished_ = true;
}

// ---------------------------------------------------------------- reader

struct GeometryStore::Connection {
  explicit Connection(const std::filesystem::path& p)
      : db(p, SqliteDb::Mode::read_only),
        query(db,
              "SELECT c.id, c.min_x, c.min_y, c.min_z, c.max_x, c.max_y, c.max_z, c.triangle_count "
              "FROM chunk_rtree r JOIN chunks c ON c.id = r.id "
              "WHERE r.max_x >= ?1 AND r.min_x <= ?2 AND r.max_y >= ?3 AND r.min_y <= ?4 "
              "AND r.max_z >= ?5 AND r.min_z <= ?6 ORDER BY c.id"),
        load(db, "SELECT origin_x, origin_y, origin_z, min_x, min_y, min_z, max_x, max_y, max_z, geometry "
                 "FROM chunks WHERE id = ?") {
    // Map the file (no read syscall per page) and keep a page cache that holds
    // the index and the chunk rows a bake's neighbourhood of cells touches.
    db.exec("PRAGMA mmap_size=4294967296; PRAGMA cache_size=-65536;");
  }
  SqliteDb db;
  SqliteStatement query;
  SqliteStatement load;
};

GeometryStore::GeometryStore(const std::filesystem::path& path, std::size_t cache_bytes)
    : path_(path), cache_cap_(cache_bytes) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path.string() + ": geometry store does not exist");
  auto c = std::make_unique<Connection>(path);
  std::map<std::string, std::string> meta;
  try {
    SqliteStatement s(c->db, "SELECT key, value FROM meta");
    while (s.step()) meta[s.column_text(0)] = s.column_text(1);
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": not a cellbake geometry store (" + e.what() + ")");
  }
  if (meta["kind"] != "cellbake-geometry-store")
    throw std::runtime_error(path.string() + ": not a cellbake geometry store");
  if (meta["schema_version"] == "1") {
    schema_version_ = 1;
  } else if (meta["schema_version"] != std::to_string(kStoreSchemaVersion)) {
    throw std::runtime_error(path.string() + ": unsupported geometry store schema version " + meta["schema_version"] +
                             " (this cellbake reads 1 and " + std::to_string(kStoreSchemaVersion) +
                             "; re-ingest the model)");
  }
  double b[6] = {0, 0, 0, 0, 0, 0};
  if (std::sscanf(meta["bounds"].c_str(), "%lf %lf %lf %lf %lf %lf", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5]) != 6)
    throw std::runtime_error(path.string() + ": geometry store metadata has no bounds");
  summary_.triangles = std::stoull(meta["triangles"]);
  if (summary_.triangles > 0) summary_.bounds = {{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
  summary_.vertices = std::stoull(meta["vertices"]);
  summary_.chunks = std::stoull(meta["chunks"]);
  summary_.skipped_degenerate = std::stoull(meta["skipped_degenerate"]);
  summary_.skipped_duplicate = std::stoull(meta["skipped_duplicate"]);
  summary_.units = meta["units"];
  summary_.content_hash = meta["content_hash"];
  if (meta["up"] == "z" || meta["up"] == "y") summary_.up = meta["up"], summary_.up_source = meta["up_source"];
  materials_ = read_materials(c->db);
  {
    SqliteStatement t(c->db, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'chunk_lods'");
    if (t.step() && t.column_int(0) > 0) {
      SqliteStatement l(c->db, "SELECT chunk_id, level, error, triangle_count FROM chunk_lods ORDER BY chunk_id, level");
      while (l.step())
        lods_[l.column_int(0)].push_back(
            {int(std::clamp<std::int64_t>(l.column_int(1), -1, 1 << 20)), l.column_double(2),
             std::uint32_t(std::clamp<std::int64_t>(l.column_int(3), 0, std::int64_t(UINT32_MAX)))});
    }
  }
  release(std::move(c));
}

std::vector<ChunkLodRef> GeometryStore::lods(std::int64_t id) const {
  const auto it = lods_.find(id);
  return it == lods_.end() ? std::vector<ChunkLodRef>{} : it->second;
}

std::shared_ptr<const Chunk> GeometryStore::load_lod(std::int64_t id, int level) const {
  const std::string where =
      path_.string() + ": level " + std::to_string(level) + " of chunk " + std::to_string(id);
  if (level < 1 || level > 15) throw std::runtime_error(where + ": no such level (levels are 1 to 15)");
  const std::int64_t key = -(id * 16 + level);  // store chunks are cached under their positive ids
  if (auto hit = cached(key)) return hit;
  auto chunk = std::make_shared<Chunk>();
  chunk->id = id;
  auto c = acquire();
  try {
    SqliteStatement q(c->db,
                      "SELECT c.origin_x, c.origin_y, c.origin_z, c.min_x, c.min_y, c.min_z, c.max_x, c.max_y, c.max_z, "
                      "l.triangle_count, l.vertex_count, l.geometry FROM chunk_lods l JOIN chunks c ON c.id = l.chunk_id "
                      "WHERE l.chunk_id = ? AND l.level = ?");
    q.bind(1, id).bind(2, std::int64_t(level));
    if (!q.step()) throw std::runtime_error("does not exist");
    chunk->origin = {q.column_double(0), q.column_double(1), q.column_double(2)};
    chunk->bounds = {{q.column_double(3), q.column_double(4), q.column_double(5)},
                     {q.column_double(6), q.column_double(7), q.column_double(8)}};
    std::size_t size = 0;
    const std::uint8_t* data = q.column_blob_data(11, size);
    decode_chunk_blob(data, size, *chunk);
    if (std::int64_t(chunk->triangle_count()) != q.column_int(9) ||
        std::int64_t(chunk->positions.size()) != q.column_int(10))
      throw std::runtime_error("blob holds " + std::to_string(chunk->triangle_count()) + " triangles, the row says " +
                               std::to_string(q.column_int(9)));
  } catch (const std::exception& e) {
    release(std::move(c));
    throw std::runtime_error(where + ": " + e.what());
  }
  release(std::move(c));
  return remember(key, std::move(chunk));
}

std::vector<Material> GeometryStore::read_materials(SqliteDb& db) const {
  std::vector<Material> out;
  const bool textured = schema_version_ >= 2;
  SqliteStatement s(db, textured ? "SELECT name, r, g, b, a, texture, texture_id, alpha_test FROM materials ORDER BY id"
                                 : "SELECT name, r, g, b, a, texture FROM materials ORDER BY id");
  while (s.step()) {
    Material m;
    m.name = s.column_text(0);
    m.color = {std::uint8_t(s.column_int(1)), std::uint8_t(s.column_int(2)), std::uint8_t(s.column_int(3)),
               std::uint8_t(s.column_int(4))};
    m.texture = s.column_text(5);
    if (textured) {
      m.texture_id = s.column_int(6);
      m.alpha_test = s.column_int(7) != 0;
    }
    out.push_back(m);
  }
  return out;
}

std::shared_ptr<const TextureImage> GeometryStore::load_texture(std::int64_t id) const {
  const std::string where = path_.string() + ": texture " + std::to_string(id);
  if (schema_version_ < 2) throw std::runtime_error(where + " does not exist (schema 1 store has no textures)");
  auto image = std::make_shared<TextureImage>();
  image->id = id;
  auto c = acquire();
  try {
    SqliteStatement s(c->db, "SELECT width, height, wrap_u, wrap_v, has_alpha, image FROM textures WHERE id = ?");
    s.bind(1, id);
    if (!s.step()) throw std::runtime_error("does not exist");
    const auto wrap = [](std::int64_t w) {
      if (w < 0 || w > 2) throw std::runtime_error("bad wrap mode " + std::to_string(w));
      return static_cast<TextureWrap>(w);
    };
    image->wrap_u = wrap(s.column_int(2));
    image->wrap_v = wrap(s.column_int(3));
    image->has_alpha = s.column_int(4) != 0;
    std::size_t size = 0;
    const std::uint8_t* data = s.column_blob_data(5, size);
    DecodedImage decoded = decode_image(data, size);
    if (decoded.width != s.column_int(0) || decoded.height != s.column_int(1))
      throw std::runtime_error("image is " + std::to_string(decoded.width) + "x" + std::to_string(decoded.height) +
                               ", the row says " + std::to_string(s.column_int(0)) + "x" +
                               std::to_string(s.column_int(1)));
    image->width = decoded.width;
    image->height = decoded.height;
    image->texels.resize(decoded.pixels.size());
    for (int y = 0; y < image->height; ++y)
      std::copy_n(decoded.pixels.begin() + std::ptrdiff_t(image->height - 1 - y) * image->width, image->width,
                  image->texels.begin() + std::ptrdiff_t(y) * image->width);
  } catch (const std::exception& e) {
    release(std::move(c));
    throw std::runtime_error(where + ": " + e.what());
  }
  release(std::move(c));
  return image;
}

GeometryStore::~GeometryStore() = default;

std::unique_ptr<GeometryStore::Connection> GeometryStore::acquire() const {
  {
    std::lock_guard<std::mutex> lock(pool_mutex_);
    if (!pool_.empty()) {
      auto c = std::move(pool_.back());
      pool_.pop_back();
      return c;
    }
  }
  return std::make_unique<Connection>(path_);
}

void GeometryStore::release(std::unique_ptr<Connection> c) const {
  std::lock_guard<std::mutex> lock(pool_mutex_);
  pool_.push_back(std::move(c));
}

std::vector<ChunkRef> GeometryStore::query(const Box3d& box) const {
  std::vector<ChunkRef> out;
  if (box.empty()) return out;
  auto c = acquire();
  auto& q = c->query;
  q.bind(1, box.lo.x).bind(2, box.hi.x).bind(3, box.lo.y).bind(4, box.hi.y).bind(5, box.lo.z).bind(6, box.hi.z);
  while (q.step()) {
    ChunkRef r;
    r.id = q.column_int(0);
    r.bounds = {{q.column_double(1), q.column_double(2), q.column_double(3)},
                {q.column_double(4), q.column_double(5), q.column_double(6)}};
    r.triangle_count = static_cast<std::uint32_t>(q.column_int(7));
    // The R*Tree is float32 and conservative; refine with the exact double bounds.
    if (r.bounds.overlaps(box)) out.push_back(r);
  }
  q.reset();
  release(std::move(c));
  return out;
}

std::shared_ptr<const Chunk> GeometryStore::cached(std::int64_t key) const {
  std::lock_guard<std::mutex> lock(cache_mutex_);
  auto it = cache_.find(key);
  if (it == cache_.end()) return nullptr;
  lru_.splice(lru_.begin(), lru_, it->second.pos);
  return it->second.chunk;
}

std::shared_ptr<const Chunk> GeometryStore::load(std::int64_t id) const {
  if (auto hit = cached(id)) return hit;
  auto chunk = std::make_shared<Chunk>();
  chunk->id = id;
  {
    auto c = acquire();
    auto& q = c->load;
    q.bind(1, id);
    if (!q.step()) {
      q.reset();
      release(std::move(c));
      throw std::runtime_error(path_.string() + ": chunk " + std::to_string(id) + " does not exist");
    }
    chunk->origin = {q.column_double(0), q.column_double(1), q.column_double(2)};
    chunk->bounds = {{q.column_double(3), q.column_double(4), q.column_double(5)},
                     {q.column_double(6), q.column_double(7), q.column_double(8)}};
    std::size_t size = 0;
    const std::uint8_t* data = q.column_blob_data(9, size);
    try {
      decode_chunk_blob(data, size, *chunk);
    } catch (const std::exception& e) {
      q.reset();
      release(std::move(c));
      throw std::runtime_error(path_.string() + ": chunk " + std::to_string(id) + ": " + e.what());
    }
    q.reset();
    release(std::move(c));
  }
  return remember(id, std::move(chunk));
}

std::shared_ptr<const Chunk> GeometryStore::remember(std::int64_t key, std::shared_ptr<const Chunk> chunk) const {
  const std::size_t bytes = chunk->positions.size() * (sizeof(Vec3f) + sizeof(Rgba8)) +
                            chunk->uvs.size() * sizeof(Uv) + chunk->normals.size() * sizeof(Vec3f) +
                            chunk->indices.size() * 4 + chunk->materials.size() * 4 + sizeof(Chunk);
  std::lock_guard<std::mutex> lock(cache_mutex_);
  auto it = cache_.find(key);
  if (it != cache_.end()) return it->second.chunk;
  lru_.push_front(key);
  cache_[key] = {chunk, lru_.begin(), bytes};
  cache_bytes_ += bytes;
  while (cache_bytes_ > cache_cap_ && lru_.size() > 1) {
    auto victim = cache_.find(lru_.back());
    cache_bytes_ -= victim->second.bytes;
    cache_.erase(victim);
    lru_.pop_back();
  }
  return chunk;
}

std::vector<SourceFileRecord> GeometryStore::sources() const {
  auto c = acquire();
  std::vector<SourceFileRecord> out;
  {
    SqliteStatement s(c->db, "SELECT path, bytes, hash, triangles FROM sources ORDER BY id");
    while (s.step())
      out.push_back({s.column_text(0), std::uint64_t(s.column_int(1)), s.column_text(2), std::uint64_t(s.column_int(3))});
  }
  release(std::move(c));
  return out;
}

std::vector<Material> GeometryStore::materials() const { return materials_; }

std::uint64_t GeometryStore::texture_count() const {
  if (schema_version_ < 2) return 0;
  auto c = acquire();
  std::uint64_t n = 0;
  {
    SqliteStatement s(c->db, "SELECT count(*) FROM textures");
    if (s.step()) n = std::uint64_t(s.column_int(0));
  }
  release(std::move(c));
  return n;
}

std::vector<ChunkRef> GeometryStore::all_chunks() const {
  auto c = acquire();
  std::vector<ChunkRef> out;
  {
    SqliteStatement s(c->db,
                      "SELECT id, min_x, min_y, min_z, max_x, max_y, max_z, triangle_count FROM chunks ORDER BY id");
    while (s.step()) {
      ChunkRef r;
      r.id = s.column_int(0);
      r.bounds = {{s.column_double(1), s.column_double(2), s.column_double(3)},
                  {s.column_double(4), s.column_double(5), s.column_double(6)}};
      r.triangle_count = static_cast<std::uint32_t>(s.column_int(7));
      out.push_back(r);
    }
  }
  release(std::move(c));
  return out;
}

// ---------------------------------------------------------------- content hash

std::string stored_content_hash(const std::filesystem::path& path) {
  const std::string where = path.string() + ": ";
  SqliteDb db(path, SqliteDb::Mode::read_only);
  {
    SqliteStatement v(db, "SELECT value FROM meta WHERE key = 'schema_version'");
    if (!v.step() || v.column_text(0) != std::to_string(kStoreSchemaVersion))
      throw std::runtime_error(where + "not a schema " + std::to_string(kStoreSchemaVersion) + " geometry store");
  }
  Hasher textures, materials, chunks;
  SqliteStatement t(db, "SELECT id, width, height, wrap_u, wrap_v, has_alpha, image FROM textures ORDER BY id");
  while (t.step()) {
    std::size_t size = 0;
    const std::uint8_t* data = t.column_blob_data(6, size);
    DecodedImage image;
    try {
      image = decode_image(data, size);
    } catch (const std::exception& e) {
      throw std::runtime_error(where + "texture " + std::to_string(t.column_int(0)) + ": " + e.what());
    }
    hash_texture(textures, t.column_int(0), t.column_int(1), t.column_int(2), t.column_int(3), t.column_int(4),
                 t.column_int(5), image.pixels);
  }
  SqliteStatement m(db, "SELECT id, name, r, g, b, a, texture, texture_id, alpha_test FROM materials ORDER BY id");
  while (m.step())
    hash_material(materials, m.column_int(0), m.column_text(1),
                  {m.column_int(2), m.column_int(3), m.column_int(4), m.column_int(5)}, m.column_text(6), m.column_int(7),
                  m.column_int(8));
  SqliteStatement c(db, "SELECT id, origin_x, origin_y, origin_z, min_x, min_y, min_z, max_x, max_y, max_z, "
                        "triangle_count, vertex_count, geometry FROM chunks ORDER BY id");
  while (c.step()) {
    double v[9];
    for (int i = 0; i < 9; ++i) v[i] = c.column_double(1 + i);
    std::size_t size = 0;
    const std::uint8_t* blob = c.column_blob_data(12, size);
    hash_chunk(chunks, c.column_int(0), v, c.column_int(10), c.column_int(11), blob, size);
  }
  Hasher lods;
  std::uint64_t lod_rows = 0;
  SqliteStatement has_lods(db, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'chunk_lods'");
  if (has_lods.step() && has_lods.column_int(0) > 0) {
    SqliteStatement l(db, "SELECT chunk_id, level, error, triangle_count, vertex_count, geometry FROM chunk_lods "
                          "ORDER BY chunk_id, level");
    while (l.step()) {
      std::size_t size = 0;
      const std::uint8_t* blob = l.column_blob_data(5, size);
      hash_chunk_lod(lods, l.column_int(0), l.column_int(1), l.column_double(2), l.column_int(3), l.column_int(4), blob,
                     size);
      ++lod_rows;
    }
  }
  return combine_content_hash(textures, materials, chunks, lods, lod_rows);
}

}  // namespace cellbake
