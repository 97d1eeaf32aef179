#include "storage/store_check.h"

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "stages/geometry.h"
#include "storage/chunk_codec.h"
#include "storage/geometry_store.h"
#include "storage/meta_values.h"
#include "storage/sqlite_db.h"

namespace cellbake {
namespace {

std::map<std::string, std::string> read_meta(SqliteDb& db, const std::filesystem::path& path) {
  std::map<std::string, std::string> meta;
  try {
    SqliteStatement s(db, "SELECT key, value FROM meta");
    while (s.step()) meta[s.column_text(0)] = s.column_text(1);
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": not a cellbake geometry store (" + e.what() + ")");
  }
  if (meta["kind"] != "cellbake-geometry-store")
    throw std::runtime_error(path.string() + ": not a cellbake geometry store");
  return meta;
}

std::uint64_t count_rows(SqliteDb& db, const std::string& table) {
  SqliteStatement s(db, "SELECT count(*) FROM " + table);
  return s.step() ? std::uint64_t(s.column_int(0)) : 0;
}

bool has_table(SqliteDb& db, const std::string& name) {
  SqliteStatement s(db, "SELECT 1 FROM sqlite_master WHERE name = ?");
  s.bind(1, name);
  return s.step();
}

// Meta `rows` against the tables' counts.
void check_rows(SqliteDb& db, const std::filesystem::path& path,
                const std::map<std::string, std::string>& meta, std::vector<StoreProblem>& problems) {
  const auto it = meta.find("rows");
  if (it == meta.end()) return;  // written before the counts were recorded
  std::map<std::string, std::uint64_t> recorded;
  std::istringstream in(it->second);
  for (std::string item; in >> item;) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      problems.push_back({0, "meta 'rows' is '" + it->second + "', not 'TABLE=COUNT ...'"});
      return;
    }
    try {
      recorded[item.substr(0, eq)] = parse_meta_u64(path, "rows", item.substr(eq + 1));
    } catch (const std::exception& e) {
      problems.push_back({0, e.what()});
      return;
    }
  }
  for (const char* table : kStoreCountedTables) {
    const auto r = recorded.find(table);
    if (r == recorded.end()) {
      problems.push_back({0, std::string("meta 'rows' records no count for table ") + table});
      continue;
    }
    if (!has_table(db, table)) {
      problems.push_back({0, std::string("table ") + table + " is missing"});
      continue;
    }
    const std::uint64_t n = count_rows(db, table);
    if (n != r->second)
      problems.push_back({0, std::string("table ") + table + " has " + std::to_string(n) +
                                 " rows, ingest wrote " + std::to_string(r->second)});
  }
  // The chunk levels: counted by stores that have them.
  const bool lod_table = has_table(db, "chunk_lods");
  const auto lods = recorded.find("chunk_lods");
  if (lods != recorded.end() && !lod_table && lods->second > 0)
    problems.push_back({0, "table chunk_lods is missing"});
  else if (lod_table) {
    const std::uint64_t n = count_rows(db, "chunk_lods");
    if (lods == recorded.end() ? n > 0 : n != lods->second)
      problems.push_back({0, "table chunk_lods has " + std::to_string(n) + " rows, ingest wrote " +
                                 (lods == recorded.end() ? std::string("none") : std::to_string(lods->second))});
  }
}

// An R-tree coordinate (float32, rounded outwards) holds the exact double
// bound: on the outer side of it, by at most a float32 rounding step.
bool holds_low(double rtree, double exact) {
  return rtree <= exact && exact - rtree <= std::max(1e-30, std::fabs(exact) * 2.5e-7);
}
bool holds_high(double rtree, double exact) {
  return rtree >= exact && rtree - exact <= std::max(1e-30, std::fabs(exact) * 2.5e-7);
}

void check_rtree(SqliteDb& db, std::vector<StoreProblem>& problems) {
  SqliteStatement s(
      db,
      "SELECT c.id, c.min_x, c.min_y, c.min_z, c.max_x, c.max_y, c.max_z, r.id, r.min_x, r.min_y, "
      "r.min_z, r.max_x, r.max_y, r.max_z FROM chunks c LEFT JOIN chunk_rtree r ON r.id = c.id "
      "ORDER BY c.id");
  while (s.step()) {
    const std::int64_t id = s.column_int(0);
    if (s.column_is_null(7)) {
      problems.push_back({id, "no R-tree entry (the bake's spatial queries never find it)"});
      continue;
    }
    bool ok = true;
    for (int a = 0; a < 3; ++a)
      ok = ok && holds_low(s.column_double(8 + a), s.column_double(1 + a)) &&
           holds_high(s.column_double(11 + a), s.column_double(4 + a));
    if (!ok) {
      char buf[512];
      std::snprintf(
          buf, sizeof buf,
          "R-tree entry (%g, %g, %g)..(%g, %g, %g) does not match its bounds (%g, %g, %g)..(%g, %g, %g)",
          s.column_double(8), s.column_double(9), s.column_double(10), s.column_double(11),
          s.column_double(12), s.column_double(13), s.column_double(1), s.column_double(2),
          s.column_double(3), s.column_double(4), s.column_double(5), s.column_double(6));
      problems.push_back({id, buf});
    }
  }
  SqliteStatement orphans(
      db,
      "SELECT r.id FROM chunk_rtree r LEFT JOIN chunks c ON c.id = r.id WHERE c.id IS NULL "
      "ORDER BY r.id");
  while (orphans.step())
    problems.push_back({orphans.column_int(0), "an R-tree entry names a chunk the store does not hold"});
}

// Every chunk blob decoded; its counts against the row's; the sums against meta.
void check_chunk_blobs(SqliteDb& db, const std::filesystem::path& path,
                       const std::map<std::string, std::string>& meta, std::vector<StoreProblem>& problems) {
  SqliteStatement s(db, "SELECT id, triangle_count, vertex_count, geometry FROM chunks ORDER BY id");
  std::uint64_t rows = 0, triangles = 0;
  while (s.step()) {
    ++rows;
    const std::int64_t id = s.column_int(0);
    triangles += std::uint64_t(std::max<std::int64_t>(0, s.column_int(1)));
    std::size_t size = 0;
    const std::uint8_t* data = s.column_blob_data(3, size);
    Chunk chunk;
    try {
      decode_chunk_blob(data, size, chunk);
    } catch (const std::exception& e) {
      problems.push_back({id, e.what()});
      continue;
    }
    if (std::int64_t(chunk.triangle_count()) != s.column_int(1) ||
        std::int64_t(chunk.positions.size()) != s.column_int(2))
      problems.push_back({id, "blob holds " + std::to_string(chunk.triangle_count()) + " triangles and " +
                                  std::to_string(chunk.positions.size()) + " vertices, the row says " +
                                  std::to_string(s.column_int(1)) + " and " +
                                  std::to_string(s.column_int(2))});
  }
  const auto compare = [&](const char* key, std::uint64_t have) {
    const auto it = meta.find(key);
    if (it == meta.end()) return;
    try {
      const std::uint64_t recorded = parse_meta_u64(path, key, it->second);
      if (recorded != have)
        problems.push_back({0, std::string("meta '") + key + "' is " + std::to_string(recorded) +
                                   ", the chunk rows hold " + std::to_string(have)});
    } catch (const std::exception& e) {
      problems.push_back({0, e.what()});
    }
  };
  compare("chunks", rows);
  compare("triangles", triangles);
  if (!has_table(db, "chunk_lods")) return;
  SqliteStatement l(db, "SELECT l.chunk_id, l.level, l.error, l.triangle_count, l.vertex_count, l.geometry, c.id "
                        "FROM chunk_lods l LEFT JOIN chunks c ON c.id = l.chunk_id ORDER BY l.chunk_id, l.level");
  while (l.step()) {
    const std::int64_t id = l.column_int(0), level = l.column_int(1);
    const std::string where = "level " + std::to_string(level) + ": ";
    if (l.column_is_null(6)) {
      problems.push_back({id, where + "the store holds no such chunk"});
      continue;
    }
    if (level < 1 || level > 15 || !std::isfinite(l.column_double(2)) || l.column_double(2) < 0) {
      problems.push_back({id, where + "level out of 1..15 or error not a finite length"});
      continue;
    }
    std::size_t size = 0;
    const std::uint8_t* data = l.column_blob_data(5, size);
    Chunk chunk;
    try {
      decode_chunk_blob(data, size, chunk);
    } catch (const std::exception& e) {
      problems.push_back({id, where + e.what()});
      continue;
    }
    if (std::int64_t(chunk.triangle_count()) != l.column_int(3) || std::int64_t(chunk.positions.size()) != l.column_int(4))
      problems.push_back({id, where + "blob holds " + std::to_string(chunk.triangle_count()) + " triangles and " +
                                  std::to_string(chunk.positions.size()) + " vertices, the row says " +
                                  std::to_string(l.column_int(3)) + " and " + std::to_string(l.column_int(4))});
  }
}

}  // namespace

std::string describe(const StoreProblem& p) {
  return p.chunk_id != 0 ? "chunk " + std::to_string(p.chunk_id) + ": " + p.reason : p.reason;
}

std::vector<StoreProblem> check_store(const std::filesystem::path& store) {
  std::vector<StoreProblem> problems;
  std::map<std::string, std::string> meta;
  {
    SqliteDb db(store, SqliteDb::Mode::read_only);
    meta = read_meta(db, store);
    check_rows(db, store, meta, problems);
    check_rtree(db, problems);
    check_chunk_blobs(db, store, meta, problems);
  }
  if (meta["schema_version"] == "1")
    return problems;  // its hash was over the source files: nothing to recompute
  try {
    const std::string hash = stored_content_hash(store);
    if (hash != meta["content_hash"])
      problems.push_back({0, "content hash mismatch (meta says " + meta["content_hash"] +
                                 ", the rows hash to " + hash + "): the store was changed after ingest"});
  } catch (const std::exception& e) {
    problems.push_back({0, e.what()});
  }
  return problems;
}

std::vector<StoreProblem> check_store_rows(const std::filesystem::path& store) {
  std::vector<StoreProblem> problems;
  SqliteDb db(store, SqliteDb::Mode::read_only);
  check_rows(db, store, read_meta(db, store), problems);
  return problems;
}

void require_sound_store(const std::filesystem::path& store, bool full) {
  if (!std::filesystem::exists(store))
    throw std::runtime_error(store.string() + ": geometry store does not exist");
  const std::vector<StoreProblem> problems = full ? check_store(store) : check_store_rows(store);
  if (problems.empty()) return;
  std::string list;
  constexpr std::size_t kShown = 5;
  for (std::size_t i = 0; i < problems.size() && i < kShown; ++i) list += "\n  " + describe(problems[i]);
  if (problems.size() > kShown) list += "\n  ... and " + std::to_string(problems.size() - kShown) + " more";
  throw std::runtime_error(store.string() + ": geometry store does not match what ingest wrote (" +
                           std::to_string(problems.size()) +
                           " problem(s)); refusing to use it (`cellbake status " + store.string() +
                           " --check` lists them; re-ingest the model):" + list);
}

std::string store_mismatch(const std::filesystem::path& database,
                           const std::optional<std::string>& baked_store_hash,
                           const std::filesystem::path& store, const std::string& store_hash) {
  if (!baked_store_hash || *baked_store_hash == store_hash) return "";
  return database.string() + " was baked from a geometry store with content hash " + *baked_store_hash +
         ", but " + store.string() + " holds " + store_hash +
         " (re-ingested or another model): its cells' near fields and far geometry name chunks of that store "
         "(--store the store it was baked from, or rebake)";
}

}  // namespace cellbake
