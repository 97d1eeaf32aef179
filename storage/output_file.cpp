#include "storage/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

std::string reason(int error) { return std::strerror(error); }

// What SQLite file `head` (the first bytes of a file) begins like, or nullptr.
const char* sqlite_file_kind(const unsigned char* head, std::size_t size) {
  static const unsigned char kDatabase[16] = {'S', 'Q', 'L', 'i', 't', 'e', ' ', 'f',
                                              'o', 'r', 'm', 'a', 't', ' ', '3', 0};
  static const unsigned char kJournal[8] = {0xd9, 0xd5, 0x05, 0xf9, 0x20, 0xa1, 0x63, 0xd7};
  if (size >= 16 && std::memcmp(head, kDatabase, 16) == 0) return "an SQLite database";
  if (size >= 4 && head[0] == 0x37 && head[1] == 0x7f && head[2] == 0x06 &&
      (head[3] == 0x82 || head[3] == 0x83))
    return "an SQLite write-ahead log (a database's -wal file)";
  if (size >= 8 && std::memcmp(head, kJournal, 8) == 0) return "an SQLite rollback journal";
  return nullptr;
}

// Refuses `target` (a regular file, links followed) when it holds an SQLite file.
void refuse_sqlite_file(const std::filesystem::path& target) {
  const int fd = ::open(target.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0)
    throw std::runtime_error(target.string() + ": cannot read it to check that it is no database (" +
                             reason(errno) + "); refusing to write an output over it");
  unsigned char head[16] = {};
  ssize_t got = 0;
  while (got < ssize_t(sizeof head)) {
    const ssize_t n = ::read(fd, head + got, sizeof head - std::size_t(got));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += n;
  }
  ::close(fd);
  if (const char* kind = sqlite_file_kind(head, std::size_t(got)))
    throw std::runtime_error(target.string() + ": is " + kind +
                             "; refusing to write an output over it (choose another output path)");
}

std::atomic<unsigned> next_temporary{0};

}  // namespace

void refuse_non_regular_target(const std::filesystem::path& path, std::string_view new_file) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw std::runtime_error(path.string() + ": cannot inspect it: " + reason(errno));
  }
  if (S_ISLNK(st.st_mode))
    throw std::runtime_error(path.string() + ": is a symbolic link; refusing to replace it with " +
                             std::string(new_file) + " (name its target)");
  if (!S_ISREG(st.st_mode))
    throw std::runtime_error(
        path.string() +
        ": is not a regular file (a directory, device or pipe); refusing to replace it with " +
        std::string(new_file));
}

void check_output_target(const std::filesystem::path& target, const InputFiles& inputs) {
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0) {  // what is there, links followed
    for (const auto& input : inputs) {
      struct stat in {};
      if (::stat(input.c_str(), &in) == 0 && in.st_dev == st.st_dev && in.st_ino == st.st_ino)
        throw std::runtime_error(
            target.string() + ": is the input " + input.string() +
            (target == input ? "" : " (a link to it, or the same file by another path)") +
            "; refusing to write an output over it (choose another output path)");
    }
    if (S_ISREG(st.st_mode)) refuse_sqlite_file(target);
  }
  refuse_non_regular_target(target, "an output");
}

OutputFile::OutputFile(const std::filesystem::path& target, const InputFiles& inputs)
    : target_(target), inputs_(inputs) {
  check_output_target(target_, inputs_);
  const std::filesystem::path folder = target_.has_parent_path() ? target_.parent_path() : ".";
  const std::string stem = target_.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-";
  for (;;) {
    temp_ = folder / (stem + std::to_string(next_temporary++));
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ >= 0) return;
    if (errno != EEXIST)
      throw std::runtime_error(target_.string() + ": cannot create a temporary file " + temp_.string() +
                               " beside it: " + reason(errno));
  }
}

OutputFile::~OutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_) ::unlink(temp_.c_str());
}

void OutputFile::fail(const char* what, int error) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(temp_.c_str());
  committed_ = true;  // nothing left to remove
  throw std::runtime_error(target_.string() + ": cannot " + what + ": " + reason(error));
}

void OutputFile::write(std::string_view bytes) {
  if (fd_ < 0) throw std::logic_error(target_.string() + ": written after commit or a failure");
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd_, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write", n < 0 ? errno : ENOSPC);
    bytes.remove_prefix(std::size_t(n));
  }
}

void OutputFile::commit() {
  if (fd_ < 0) throw std::logic_error(target_.string() + ": committed twice or after a failure");
  // On disk before the rename, so a crash never leaves a renamed empty file.
  if (::fsync(fd_) != 0 && errno != EINVAL) fail("write", errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("write", errno);
  try {
    check_output_target(target_, inputs_);  // nothing was put there meanwhile that must stay
  } catch (...) {
    ::unlink(temp_.c_str());
    committed_ = true;
    throw;
  }
  if (::rename(temp_.c_str(), target_.c_str()) != 0) fail("rename its temporary file onto it", errno);
  committed_ = true;
}

void write_output_file(const std::filesystem::path& target, std::string_view bytes,
                       const InputFiles& inputs) {
  OutputFile out(target, inputs);
  out.write(bytes);
  out.commit();
}

}  // namespace cellbake
