#include "storage/cell_db_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iterator>
#include <stdexcept>
#include <string>
#include <utility>

namespace cellbake {
namespace {

// The identity lock's bytes of the database file: far beyond the bytes SQLite
// locks (around 1 GiB) and beyond any database, so readers and SQLite's own
// locks never meet them. The holder locks kIdentityByte (the exclusion) and
// kHolderBase + (purpose index << 32) + pid (what a refused opener reports).
constexpr off_t kIdentityByte = off_t(1) << 62;
constexpr off_t kHolderBase = kIdentityByte + 1;
constexpr const char* kPurposes[] = {"used", "baked", "merged into", "repaired"};
constexpr off_t kHolderRange = off_t(std::size(kPurposes)) << 32;

off_t purpose_index(const char* purpose) {
  for (std::size_t i = 1; i < std::size(kPurposes); ++i)
    if (std::strcmp(purpose, kPurposes[i]) == 0) return off_t(i);
  return 0;
}

// What the holder wrote in the lock file: "PID PURPOSE" (e.g. "4711 baked"); the pid is "?" while it has not
// written yet.
std::pair<std::string, std::string> read_holder(int fd) {
  char buf[128] = {};
  const ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
  std::string text = n > 0 ? std::string(buf, std::size_t(n)) : std::string();
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  const auto space = text.find(' ');
  if (text.empty()) return {"?", "used"};
  if (space == std::string::npos) return {text, "used"};
  return {text.substr(0, space), text.substr(space + 1)};
}

[[noreturn]] void io_error(const std::filesystem::path& file, const char* what) {
  throw std::runtime_error(file.string() + ": cannot " + what +
                           " the bake lock file: " + std::strerror(errno));
}

[[noreturn]] void refuse(const std::filesystem::path& database, const std::string& purpose,
                         const std::string& pid, const std::string& where) {
  throw std::runtime_error("database " + database.string() + " is being " + purpose + " by pid " + pid +
                           " (" + where + "); wait for it to finish or stop it");
}

// Write-locks `length` bytes from `start` of `fd`'s file for this open file
// description; false when another one holds any of them.
bool lock_range(int fd, off_t start, off_t length, const std::filesystem::path& file) {
  struct flock range {};
  range.l_type = F_WRLCK;
  range.l_whence = SEEK_SET;
  range.l_start = start;
  range.l_len = length;
  if (fcntl(fd, F_OFD_SETLK, &range) == 0) return true;
  if (errno == EAGAIN || errno == EACCES) return false;
  throw std::runtime_error(file.string() +
                           ": cannot lock the database file for the bake: " + std::strerror(errno));
}

// The pid and purpose the identity lock's holder recorded in its holder byte ("?" and "used" when unseen).
std::pair<std::string, std::string> identity_holder(int fd) {
  struct flock probe {};
  probe.l_type = F_WRLCK;
  probe.l_whence = SEEK_SET;
  probe.l_start = kHolderBase;
  probe.l_len = kHolderRange;
  if (fcntl(fd, F_OFD_GETLK, &probe) != 0 || probe.l_type == F_UNLCK) return {"?", "used"};
  const off_t code = probe.l_start - kHolderBase;
  return {std::to_string(code & 0xffffffff), kPurposes[code >> 32]};
}

// Opens the database file for the identity lock, creating it empty when
// absent (`created` then). Throws naming it when it is not a regular file.
int open_database(const std::filesystem::path& database, bool& created) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    struct stat st {};
    if (::stat(database.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      throw std::runtime_error(
          database.string() +
          ": is not a regular file (a directory, device or pipe); refusing to write a cell "
          "database there");
    int fd = ::open(database.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0 && errno == ENOENT) {
      fd = ::open(database.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
      if (fd < 0 && errno == EEXIST) continue;  // made meanwhile (or a dangling symbolic link)
      created = fd >= 0;
    }
    if (fd < 0)
      throw std::runtime_error(database.string() +
                               ": cannot open the database file to lock it: " + std::strerror(errno));
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd);
      throw std::runtime_error(database.string() + ": is not a regular file (a directory, device or pipe)");
    }
    return fd;
  }
  throw std::runtime_error(database.string() +
                           ": cannot open the database file to lock it (a dangling symbolic link?)");
}

}  // namespace

std::filesystem::path CellDbLock::lock_path(const std::filesystem::path& database) {
  std::error_code ec;
  std::filesystem::path real = std::filesystem::weakly_canonical(std::filesystem::absolute(database, ec), ec);
  if (ec) real = database;
  return std::filesystem::path(real.string() + ".lock");
}

CellDbLock::CellDbLock(const std::filesystem::path& database, const char* purpose)
    : path_(lock_path(database)), database_(database) {
  // A holder removes the file when it releases the lock; a file locked after
  // its removal is not the one at the path any more, so check and retry.
  for (int attempt = 0;; ++attempt) {
    const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd < 0) io_error(path_, "create");
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      const auto [pid, holder_purpose] =
          err == EWOULDBLOCK ? read_holder(fd) : std::pair<std::string, std::string>();
      ::close(fd);
      if (err != EWOULDBLOCK) {
        errno = err;
        io_error(path_, "lock");
      }
      refuse(database, holder_purpose, pid, "lock file " + path_.string());
    }
    struct stat held {
    }, at_path{};
    if (fstat(fd, &held) == 0 && ::stat(path_.c_str(), &at_path) == 0 && held.st_ino == at_path.st_ino &&
        held.st_dev == at_path.st_dev) {
      fd_ = fd;
      break;
    }
    ::close(fd);
    if (attempt > 100) throw std::runtime_error(path_.string() + ": the bake lock file keeps being replaced");
  }
  try {
    database_fd_ = open_database(database, created_database_);
    if (!lock_range(database_fd_, kIdentityByte, 1, database)) {
      const auto [pid, holder_purpose] = identity_holder(database_fd_);
      refuse(database, holder_purpose, pid,
             "the same file under another name: a link, or a path through one");
    }
    const off_t holder = kHolderBase + (purpose_index(purpose) << 32) + off_t(::getpid() & 0xffffffff);
    if (!lock_range(database_fd_, holder, 1, database))
      throw std::runtime_error(database.string() + ": cannot record this process in the bake lock");
    const std::string pid = std::to_string(::getpid()) + " " + purpose + "\n";
    if (ftruncate(fd_, 0) != 0 || pwrite(fd_, pid.data(), pid.size(), 0) != ssize_t(pid.size()))
      io_error(path_, "write");
  } catch (...) {
    release();
    throw;
  }
}

CellDbLock::~CellDbLock() { release(); }

void CellDbLock::release() {
  if (database_fd_ >= 0) {
    // A database this lock created and nobody wrote is removed again (while still locked).
    struct stat held {
    }, at_path{};
    if (created_database_ && fstat(database_fd_, &held) == 0 && held.st_size == 0 &&
        ::stat(database_.c_str(), &at_path) == 0 && held.st_ino == at_path.st_ino &&
        held.st_dev == at_path.st_dev)
      ::unlink(database_.c_str());
    ::close(database_fd_);
    database_fd_ = -1;
  }
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // while still locked: a waiting opener retries on the new file
  ::close(fd_);
  fd_ = -1;
}

}  // namespace cellbake
