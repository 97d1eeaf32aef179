#include "storage/cell_db_merge.h"

#include <stdexcept>
#include <string>
#include <vector>

#include "storage/cell_check.h"
#include "storage/sqlite_db.h"

namespace cellbake {
namespace {

// The target's existing row of a cell compared with the source's.
enum class CopyDecision { copy, unchanged, keep_done };

CopyDecision decide(const CellStamp* existing, const CellStamp& incoming) {
  if (!existing) return CopyDecision::copy;
  if (existing->status == incoming.status && existing->input_hash == incoming.input_hash &&
      existing->content_hash == incoming.content_hash)
    return CopyDecision::unchanged;
  if (existing->status == "done" && incoming.status != "done") return CopyDecision::keep_done;
  return CopyDecision::copy;
}

// Copies the rows of cells `to_copy` from `source` into `target`, one transaction per cell.
void copy_rows(CellDb& target, const CellDb& source, const std::vector<std::int64_t>& to_copy, CellCopyCounts& counts);

}  // namespace

CellCopyCounts copy_cells(CellDb& target, const CellDb& source, const CellCheckContext& context) {
  if (source.schema_version() != target.schema_version())
    throw std::runtime_error(source.path().string() + ": cell database schema version " +
                             std::to_string(source.schema_version()) + " differs from " + target.path().string() +
                             "'s " + std::to_string(target.schema_version()) +
                             " (open it read-write once, e.g. with `cellbake bake`, to migrate it)");
  const auto have = target.stamps();
  const auto incoming = source.stamps();
  std::vector<std::int64_t> to_copy;
  CellCopyCounts counts;
  for (const auto& [id, stamp] : incoming) {
    auto it = have.find(id);
    switch (decide(it == have.end() ? nullptr : &it->second, stamp)) {
      case CopyDecision::copy: to_copy.push_back(id); break;
      case CopyDecision::unchanged: ++counts.unchanged; break;
      case CopyDecision::keep_done: ++counts.kept_done; break;
    }
  }
  if (to_copy.empty()) return counts;
  // Verified before anything is written: hashes recomputed, blobs decoded.
  std::string damaged;
  std::size_t n_damaged = 0;
  for (std::int64_t id : to_copy)
    if (const std::string reason = check_cell(source, id, context); !reason.empty() && ++n_damaged <= 5)
      damaged += "\n  cell " + std::to_string(id) + ": " + reason;
  if (n_damaged)
    throw std::runtime_error(source.path().string() + ": " + std::to_string(n_damaged) +
                             " damaged cell(s); refusing to merge this shard (`cellbake status --repair " +
                             source.path().string() + "` marks them pending, then rerun its bake):" + damaged);
  try {
    copy_rows(target, source, to_copy, counts);
  } catch (const std::exception& e) {
    throw std::runtime_error(source.path().string() + ": merging its cells into " + target.path().string() +
                             " failed: " + e.what());
  }
  return counts;
}

namespace {

void copy_rows(CellDb& target, const CellDb& source, const std::vector<std::int64_t>& to_copy, CellCopyCounts& counts) {

  // A second connection to the target (WAL allows it) with the source
  // attached; both are the same schema version, so SELECT * matches column
  // for column (far_geometry's `level` of version 5 included: a shard of
  // another version was refused above).
  SqliteDb db(target.path(), SqliteDb::Mode::read_write_create);
  db.exec("PRAGMA synchronous=NORMAL");  // as CellDb: WAL stays consistent, a crash loses at most the last cells
  {
    SqliteStatement attach(db, "ATTACH DATABASE ? AS source");
    attach.bind(1, source.attach_uri()).run();  // read-only, and immutable when its folder is
  }
  {
    const bool far_choice = target.schema_version() >= 4;
    SqliteStatement del_faces(db, "DELETE FROM main.faces WHERE cell_id=?");
    SqliteStatement del_choice(db, far_choice ? "DELETE FROM main.far_choice WHERE cell_id=?" : "SELECT ?");
    SqliteStatement ins_choice(
        db, far_choice ? "INSERT INTO main.far_choice SELECT * FROM source.far_choice WHERE cell_id=?" : "SELECT ?");
    SqliteStatement del_geometry(db, far_choice ? "DELETE FROM main.far_geometry WHERE cell_id=?" : "SELECT ?");
    SqliteStatement ins_geometry(
        db, far_choice ? "INSERT INTO main.far_geometry SELECT * FROM source.far_geometry WHERE cell_id=?" : "SELECT ?");
    SqliteStatement del_samples(db, "DELETE FROM main.samples WHERE cell_id=?");
    SqliteStatement del_cell(db, "DELETE FROM main.cells WHERE id=?");
    SqliteStatement ins_cell(db, "INSERT INTO main.cells SELECT * FROM source.cells WHERE id=?");
    SqliteStatement ins_samples(db, "INSERT INTO main.samples SELECT * FROM source.samples WHERE cell_id=?");
    SqliteStatement ins_faces(db, "INSERT INTO main.faces SELECT * FROM source.faces WHERE cell_id=?");
    for (std::int64_t id : to_copy) {
      SqliteTransaction tx(db);
      for (SqliteStatement* s :
           {&del_faces, &del_choice, &del_geometry, &del_samples, &del_cell, &ins_cell, &ins_samples, &ins_faces,
            &ins_choice, &ins_geometry})
        s->bind(1, id).run();
      tx.commit();
      ++counts.copied;
    }
  }
  db.exec("DETACH DATABASE source");
}

}  // namespace

std::map<std::string, std::string> metas_with_prefix(const CellDb& cells, const std::string& prefix) {
  SqliteDb db(cells.path(), SqliteDb::Mode::read_only);
  SqliteStatement s(db, "SELECT key, value FROM meta WHERE substr(key, 1, ?) = ? ORDER BY key");
  s.bind(1, std::int64_t(prefix.size())).bind(2, prefix);
  std::map<std::string, std::string> out;
  while (s.step()) out[s.column_text(0)] = s.column_text(1);
  return out;
}

}  // namespace cellbake
