// A thin RAII layer over SQLite: a connection and prepared statements with
// typed binds/columns. Every error throws std::runtime_error naming the
// database file and SQLite's message. This header hides sqlite3.h from users.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace cellbake {

class SqliteDb;

class SqliteStatement {
 public:
  SqliteStatement(SqliteDb& db, std::string_view sql);
  ~SqliteStatement();
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  // Binds are 1-based, like SQLite's.
  SqliteStatement& bind(int index, std::int64_t value);
  SqliteStatement& bind(int index, double value);
  SqliteStatement& bind(int index, std::string_view text);
  SqliteStatement& bind_blob(int index, const void* data, std::size_t size);
  SqliteStatement& bind_null(int index);
  // Steps once: true when a row is available, false when done.
  bool step();
  // Steps to completion (for statements returning no rows) and resets.
  void run();
  void reset();

  // Columns are 0-based.
  std::int64_t column_int(int col) const;
  double column_double(int col) const;
  std::string column_text(int col) const;
  std::vector<std::uint8_t> column_blob(int col) const;
  const std::uint8_t* column_blob_data(int col, std::size_t& size) const;
  bool column_is_null(int col) const;

 private:
  SqliteDb& db_;
  sqlite3_stmt* stmt_ = nullptr;
};

class SqliteDb {
 public:
  enum class Mode { read_only, read_write_create };
  // Opens `file`; throws naming it. A read-only open of a database whose writer
  // was killed mid-transaction (a hot journal) first lets SQLite roll that
  // transaction back through a short writable connection, as any writable open
  // would; it throws when the file is not writable then. A read-only open of a
  // WAL database whose folder (or medium) cannot hold its -shm file opens it
  // as immutable (every page read from the file itself) when no -wal file with
  // content is beside it, and throws naming that -wal file when one is.
  SqliteDb(const std::filesystem::path& file, Mode mode);
  ~SqliteDb();
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;

  void exec(std::string_view sql);
  std::int64_t last_insert_rowid() const;
  const std::filesystem::path& file() const { return file_; }
  sqlite3* handle() { return db_; }
  [[noreturn]] void fail(const std::string& what) const;
  // True when this read-only connection reads the file as immutable (a read-only folder).
  bool immutable() const { return immutable_; }
  // The URI that ATTACHes this file read-only the way this connection reads it
  // (immutable in a read-only folder).
  std::string attach_uri() const;
  // True for SQLite's (extended) result codes of a first read that failed
  // because the WAL's -shm file cannot be created beside the database.
  static bool cannot_create_wal_files(int sqlite_result_code);

 private:
  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
  bool immutable_ = false;
};

// Begins a transaction on construction; rolls back on destruction unless committed.
class SqliteTransaction {
 public:
  explicit SqliteTransaction(SqliteDb& db, bool immediate = true);
  ~SqliteTransaction();
  void commit();

 private:
  SqliteDb& db_;
  bool done_ = false;
};

}  // namespace cellbake
