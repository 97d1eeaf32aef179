#include "storage/database_kind.h"

#include "storage/sqlite_db.h"

namespace cellbake {

DatabaseKind database_kind(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return DatabaseKind::other;
  try {
    SqliteDb db(path, SqliteDb::Mode::read_only);
    SqliteStatement s(db, "SELECT value FROM meta WHERE key = 'kind'");
    if (s.step() && s.column_text(0) == "cellbake-geometry-store") return DatabaseKind::geometry_store;
  } catch (const std::exception&) {
  }
  return DatabaseKind::other;
}

}  // namespace cellbake
