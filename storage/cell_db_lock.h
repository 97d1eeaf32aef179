// One writer per cell database: an exclusive flock() on DB.lock (next to the
// database) held for a whole bake, merge into it, or repair. The kernel drops
// the lock when its process dies, kill -9 included, so a crashed bake never
// leaves a stale lock; the file holds the owner's pid and purpose for the message.
#pragma once

#include <filesystem>

namespace cellbake {

class CellDbLock {
 public:
  // Takes the lock on `database` (the lock file is `database` + ".lock").
  // `purpose` names this work for others' refusals ("baked", "merged into",
  // "repaired"). Throws std::runtime_error "database X is being <holder's
  // purpose> by pid N (lock file X.lock); ..." when another process holds it,
  // and on I/O errors naming the lock file. Never blocks.
  CellDbLock(const std::filesystem::path& database, const char* purpose);
  // Releases the lock and removes the lock file.
  ~CellDbLock();
  CellDbLock(const CellDbLock&) = delete;
  CellDbLock& operator=(const CellDbLock&) = delete;

  // The lock file of `database`.
  static std::filesystem::path lock_path(const std::filesystem::path& database);

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace cellbake
