// One writer per cell database, whatever name it is reached by: held for a
// whole bake, merge into it, or repair. Two locks, both dropped by the kernel
// when their process dies (kill -9 included), so a crashed bake never leaves a
// stale lock:
//  - an open-file-description lock (F_OFD_SETLK) on a byte range of the
//    database file itself, far beyond any byte SQLite locks: it follows the
//    file's identity (device and inode), so a symbolic link or a hard link to
//    a database that is being baked is refused too. The holder also locks one
//    byte whose offset encodes its pid and purpose, which a refused opener reads
//    back with F_OFD_GETLK;
//  - an flock() on DB.lock next to the database (its real path, symbolic links
//    resolved), which holds the owner's pid and purpose for people looking at
//    the folder and excludes older cellbake versions, which lock only that file.
#pragma once

#include <filesystem>

namespace cellbake {

class CellDbLock {
 public:
  // Takes both locks on `database` (created empty when it does not exist yet,
  // and removed again on release if it is still empty then). `purpose` names
  // this work for others' refusals ("baked", "merged into", "repaired").
  // Throws std::runtime_error "database X is being <holder's purpose> by pid N
  // (lock file L); ..." when another process holds it under any of its names,
  // "X: is not a regular file ..." for a directory, device or pipe, and on I/O
  // errors naming the file. Never blocks.
  CellDbLock(const std::filesystem::path& database, const char* purpose);
  // Releases the locks and removes the lock file.
  ~CellDbLock();
  CellDbLock(const CellDbLock&) = delete;
  CellDbLock& operator=(const CellDbLock&) = delete;

  // The lock file of `database`: its real path (symbolic links resolved) + ".lock".
  static std::filesystem::path lock_path(const std::filesystem::path& database);

 private:
  void release();

  std::filesystem::path path_, database_;
  int fd_ = -1;           // the flock'd lock file
  int database_fd_ = -1;  // holds the identity lock on the database file
  bool created_database_ = false;
};

}  // namespace cellbake
