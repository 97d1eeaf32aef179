#include "storage/cell_db_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

namespace cellbake {
namespace {

// What the holder wrote: "PID PURPOSE" (e.g. "4711 baked"); the pid is "?" while it has not written yet.
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
  throw std::runtime_error(file.string() + ": cannot " + what + " the bake lock file: " + std::strerror(errno));
}

}  // namespace

std::filesystem::path CellDbLock::lock_path(const std::filesystem::path& database) {
  return std::filesystem::path(database.string() + ".lock");
}

CellDbLock::CellDbLock(const std::filesystem::path& database, const char* purpose) : path_(lock_path(database)) {
  // A holder removes the file when it releases the lock; a file locked after
  // its removal is not the one at the path any more, so check and retry.
  for (int attempt = 0;; ++attempt) {
    const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd < 0) io_error(path_, "create");
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      const auto [pid, holder_purpose] = err == EWOULDBLOCK ? read_holder(fd) : std::pair<std::string, std::string>();
      ::close(fd);
      if (err != EWOULDBLOCK) {
        errno = err;
        io_error(path_, "lock");
      }
      throw std::runtime_error("database " + database.string() + " is being " + holder_purpose + " by pid " + pid +
                               " (lock file " + path_.string() + "); wait for it to finish or stop it");
    }
    struct stat held {}, at_path {};
    if (fstat(fd, &held) == 0 && ::stat(path_.c_str(), &at_path) == 0 && held.st_ino == at_path.st_ino &&
        held.st_dev == at_path.st_dev) {
      fd_ = fd;
      break;
    }
    ::close(fd);
    if (attempt > 100) throw std::runtime_error(path_.string() + ": the bake lock file keeps being replaced");
  }
  const std::string pid = std::to_string(::getpid()) + " " + purpose + "\n";
  if (ftruncate(fd_, 0) != 0 || pwrite(fd_, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
    ::close(fd_);
    io_error(path_, "write");
  }
}

CellDbLock::~CellDbLock() {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // while still locked: a waiting opener retries on the new file
  ::close(fd_);
}

}  // namespace cellbake
