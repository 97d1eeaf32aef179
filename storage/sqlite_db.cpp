#include "storage/sqlite_db.h"

#include <sqlite3.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

namespace cellbake {

namespace {

// SQLite's URI for `file` (absolute; every byte but [A-Za-z0-9-._~/]
// percent-encoded, so '?', '#' and '%' in names stay names) with `query`.
std::string file_uri(const std::filesystem::path& file, const std::string& query) {
  std::error_code ec;
  const std::string path = std::filesystem::absolute(file, ec).string();
  std::string uri = "file://";
  static const char* kHex = "0123456789ABCDEF";
  for (const char c : ec ? file.string() : path) {
    const auto byte = static_cast<unsigned char>(c);
    const bool alnum =
        (byte >= '0' && byte <= '9') || (byte >= 'A' && byte <= 'Z') || (byte >= 'a' && byte <= 'z');
    if (alnum || c == '-' || c == '.' || c == '_' || c == '~' || c == '/') {
      uri += c;
    } else {
      uri += '%';
      uri += kHex[byte >> 4];
      uri += kHex[byte & 15];
    }
  }
  return query.empty() ? uri : uri + "?" + query;
}

// Opens `file` through its URI with `query` and `flags` (and no mutex: one
// thread per connection); throws naming the file.
sqlite3* open_connection(const std::filesystem::path& file, int flags, const std::string& query = "") {
  sqlite3* db = nullptr;
  const std::string uri = file_uri(file, query);
  if (sqlite3_open_v2(uri.c_str(), &db, flags | SQLITE_OPEN_URI | SQLITE_OPEN_NOMUTEX, nullptr) !=
      SQLITE_OK) {
    std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw std::runtime_error(file.string() + ": cannot open database: " + msg);
  }
  sqlite3_busy_timeout(db, 60000);
  sqlite3_extended_result_codes(db, 1);
  return db;
}

// Reads the schema (the first read of a connection, where SQLite finds a hot
// journal or a WAL needing recovery); SQLite's extended result code.
int read_schema(sqlite3* db) { return sqlite3_exec(db, "PRAGMA schema_version", nullptr, nullptr, nullptr); }

bool needs_writable_recovery(int rc) {
  return rc == SQLITE_READONLY_ROLLBACK || rc == SQLITE_READONLY_RECOVERY || rc == SQLITE_READONLY_CANTINIT;
}

}  // namespace

bool SqliteDb::cannot_create_wal_files(int rc) {
  // A WAL database's first read creates DB-shm (and DB-wal): READONLY_DIRECTORY
  // when the folder (or the medium) is read-only, CANTOPEN when a -wal file
  // is there but its -shm cannot be made.
  return rc == SQLITE_READONLY_DIRECTORY || (rc & 0xff) == SQLITE_CANTOPEN;
}

namespace {

// True when this process may not create files beside `file` (permissions, a
// read-only mount): the only case an immutable open is taken for, so that an
// unrelated failure (no file descriptors left) never turns into one.
bool folder_is_read_only(const std::filesystem::path& file) {
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::absolute(file, ec).parent_path();
  return !ec && ::access(folder.c_str(), W_OK) != 0 && (errno == EACCES || errno == EROFS || errno == EPERM);
}

// Opens `file` as immutable (no -shm, no locks, no -wal read), which SQLite
// allows for a database no one changes: used only where the folder cannot hold
// the WAL's files. Throws naming the file when a -wal file with content is
// beside it: those committed changes would be silently missing.
sqlite3* open_immutable(const std::filesystem::path& file, int failed_rc) {
  const std::filesystem::path wal = file.string() + "-wal";
  std::error_code ec;
  const auto wal_bytes = std::filesystem::file_size(wal, ec);
  if (!ec && wal_bytes > 0)
    throw std::runtime_error(
        file.string() + ": cannot be read in a read-only folder: its write-ahead log " + wal.string() +
        " holds " + std::to_string(wal_bytes) +
        " bytes of changes not yet checkpointed into it, which SQLite reads only with write access to the "
        "folder "
        "(to create its -shm file); checkpoint it where the folder is writable (sqlite3 " +
        file.string() +
        " 'PRAGMA wal_checkpoint(TRUNCATE)'), or copy the database with its -wal file into a writable folder "
        "(" +
        sqlite3_errstr(failed_rc) + ")");
  sqlite3* db = open_connection(file, SQLITE_OPEN_READONLY, "immutable=1");
  if (const int rc = read_schema(db); rc != SQLITE_OK) {
    const std::string msg = sqlite3_errmsg(db);
    sqlite3_close_v2(db);
    throw std::runtime_error(file.string() +
                             ": cannot read it as an immutable database in a read-only folder: " + msg);
  }
  return db;
}

}  // namespace

SqliteDb::SqliteDb(const std::filesystem::path& file, Mode mode) : file_(file) {
  if (mode == Mode::read_write_create) {
    db_ = open_connection(file, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
    return;
  }
  db_ = open_connection(file, SQLITE_OPEN_READONLY);
  const int rc = read_schema(db_);
  if (cannot_create_wal_files(rc) && folder_is_read_only(file)) {
    sqlite3_close_v2(db_);
    db_ = nullptr;
    db_ = open_immutable(file, rc);
    immutable_ = true;
    return;
  }
  if (!needs_writable_recovery(rc)) return;
  // A writer killed inside a transaction left a hot rollback journal (or a WAL
  // index to rebuild) that only a writable connection may apply. Apply it as
  // SQLite does on any writable open, which restores the last committed state
  // and changes nothing else, then read through a read-only connection again.
  sqlite3_close_v2(db_);
  db_ = nullptr;
  sqlite3* writer = nullptr;
  try {
    writer = open_connection(file, SQLITE_OPEN_READWRITE);
  } catch (const std::exception& e) {
    throw std::runtime_error(
        file.string() +
        ": needs recovering with write access, which this user lacks (a process writing it "
        "was killed mid-transaction, or its WAL index cannot be read without writing) (" +
        e.what() + ")");
  }
  const int recovered = read_schema(writer);
  const std::string msg = sqlite3_errmsg(writer);
  sqlite3_close_v2(writer);
  if (recovered != SQLITE_OK)
    throw std::runtime_error(file.string() + ": recovering after a killed writer: " + msg);
  db_ = open_connection(file, SQLITE_OPEN_READONLY);
}

SqliteDb::~SqliteDb() { sqlite3_close_v2(db_); }

std::string SqliteDb::attach_uri() const { return file_uri(file_, immutable_ ? "immutable=1" : "mode=ro"); }

void SqliteDb::fail(const std::string& what) const {
  throw std::runtime_error(file_.string() + ": " + what + ": " + sqlite3_errmsg(db_));
}

void SqliteDb::exec(std::string_view sql) {
  char* err = nullptr;
  std::string s(sql);
  if (sqlite3_exec(db_, s.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw std::runtime_error(file_.string() + ": " + msg + " (in: " + s.substr(0, 80) + ")");
  }
}

std::int64_t SqliteDb::last_insert_rowid() const { return sqlite3_last_insert_rowid(db_); }

SqliteStatement::SqliteStatement(SqliteDb& db, std::string_view sql) : db_(db) {
  if (sqlite3_prepare_v2(db.handle(), sql.data(), static_cast<int>(sql.size()), &stmt_, nullptr) != SQLITE_OK)
    db_.fail("cannot prepare '" + std::string(sql.substr(0, 80)) + "'");
}

SqliteStatement::~SqliteStatement() { sqlite3_finalize(stmt_); }

SqliteStatement& SqliteStatement::bind(int index, std::int64_t value) {
  if (sqlite3_bind_int64(stmt_, index, value) != SQLITE_OK) db_.fail("bind");
  return *this;
}
SqliteStatement& SqliteStatement::bind(int index, double value) {
  if (sqlite3_bind_double(stmt_, index, value) != SQLITE_OK) db_.fail("bind");
  return *this;
}
SqliteStatement& SqliteStatement::bind(int index, std::string_view text) {
  if (sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT) !=
      SQLITE_OK)
    db_.fail("bind");
  return *this;
}
SqliteStatement& SqliteStatement::bind_blob(int index, const void* data, std::size_t size) {
  if (sqlite3_bind_blob64(stmt_, index, size ? data : "", size, SQLITE_TRANSIENT) != SQLITE_OK)
    db_.fail("bind");
  return *this;
}
SqliteStatement& SqliteStatement::bind_null(int index) {
  if (sqlite3_bind_null(stmt_, index) != SQLITE_OK) db_.fail("bind");
  return *this;
}

bool SqliteStatement::step() {
  int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  db_.fail("step");
}

void SqliteStatement::run() {
  while (step()) {
  }
  reset();
}

void SqliteStatement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

std::int64_t SqliteStatement::column_int(int col) const { return sqlite3_column_int64(stmt_, col); }
double SqliteStatement::column_double(int col) const { return sqlite3_column_double(stmt_, col); }
std::string SqliteStatement::column_text(int col) const {
  const unsigned char* t = sqlite3_column_text(stmt_, col);
  return t ? std::string(reinterpret_cast<const char*>(t), sqlite3_column_bytes(stmt_, col)) : std::string();
}
const std::uint8_t* SqliteStatement::column_blob_data(int col, std::size_t& size) const {
  const void* p = sqlite3_column_blob(stmt_, col);
  size = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col));
  return static_cast<const std::uint8_t*>(p);
}
std::vector<std::uint8_t> SqliteStatement::column_blob(int col) const {
  std::size_t size = 0;
  const std::uint8_t* p = column_blob_data(col, size);
  return p ? std::vector<std::uint8_t>(p, p + size) : std::vector<std::uint8_t>();
}
bool SqliteStatement::column_is_null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }

SqliteTransaction::SqliteTransaction(SqliteDb& db, bool immediate) : db_(db) {
  db_.exec(immediate ? "BEGIN IMMEDIATE" : "BEGIN");
}
SqliteTransaction::~SqliteTransaction() {
  if (!done_) {
    try {
      db_.exec("ROLLBACK");
    } catch (...) {
    }
  }
}
void SqliteTransaction::commit() {
  db_.exec("COMMIT");
  done_ = true;
}

}  // namespace cellbake
