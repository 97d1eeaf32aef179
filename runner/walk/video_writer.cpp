#include "runner/walk/video_writer.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace cellbake {
namespace {

// Runs `argv` with stdout to a pipe and returns what it printed ("" when it cannot start).
std::string output_of(const std::vector<std::string>& argv) {
  int fds[2];
  if (pipe(fds) != 0) return "";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  std::string out;
  if (rc == 0) {
    char buf[4096];
    for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0 || (n < 0 && errno == EINTR);)
      if (n > 0) out.append(buf, std::size_t(n));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  close(fds[0]);
  return out;
}

std::string fps_text(double fps) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", fps);
  return buf;
}

}  // namespace

std::optional<std::filesystem::path> find_ffmpeg() {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    if (dir.empty()) continue;
    const std::filesystem::path candidate = std::filesystem::path(dir) / "ffmpeg";
    if (access(candidate.c_str(), X_OK) == 0 && std::filesystem::is_regular_file(candidate)) return candidate;
  }
  return std::nullopt;
}

VideoWriter::VideoWriter(const std::filesystem::path& ffmpeg, const std::filesystem::path& out, int width, int height,
                         double fps, const std::filesystem::path& log)
    : out_(out), tmp_(out.parent_path() / (out.stem().string() + ".part.mp4")), log_(log), width_(width),
      height_(height) {
  if (width < 1 || height < 1 || !(fps > 0)) throw std::invalid_argument("video: bad frame size or rate");
  codec_ = output_of({ffmpeg.string(), "-hide_banner", "-encoders"}).find(" libx264 ") != std::string::npos
               ? "libx264"
               : "mpeg4";
  std::vector<std::string> argv{ffmpeg.string(), "-hide_banner", "-loglevel", "error", "-nostdin", "-y",
                                "-f", "rawvideo", "-pixel_format", "rgb24", "-video_size",
                                std::to_string(width) + "x" + std::to_string(height), "-framerate", fps_text(fps),
                                "-i", "pipe:0", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", codec_};
  if (codec_ == "libx264")
    argv.insert(argv.end(), {"-preset", "veryfast", "-crf", "20", "-threads", "2"});
  else
    argv.insert(argv.end(), {"-q:v", "3"});
  argv.insert(argv.end(), {"-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4", tmp_.string()});
  // A socket rather than a pipe: send() with MSG_NOSIGNAL reports a stopped
  // ffmpeg as EPIPE without raising SIGPIPE in the whole process.
  int sv[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
    throw std::runtime_error(std::string("video: socketpair: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, sv[1], 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int rc = posix_spawn(&pid_, ffmpeg.c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(sv[1]);
  if (rc != 0) {
    close(sv[0]);
    pid_ = -1;
    throw std::runtime_error("video: cannot start " + ffmpeg.string() + ": " + std::strerror(rc));
  }
  fd_ = sv[0];
}

VideoWriter::~VideoWriter() {
  if (pid_ > 0) {
    stop();
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
  }
}

void VideoWriter::stop() {
  if (fd_ >= 0) close(fd_), fd_ = -1;
  if (pid_ > 0) {
    kill(pid_, SIGTERM);
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
  }
}

void VideoWriter::write(const std::vector<unsigned char>& rgb) {
  if (rgb.size() != std::size_t(width_) * std::size_t(height_) * 3)
    throw std::invalid_argument("video: frame of " + std::to_string(rgb.size()) + " bytes, expected " +
                                std::to_string(std::size_t(width_) * height_ * 3));
  if (fd_ < 0) throw std::runtime_error("video: the encoder has finished");
  std::size_t sent = 0;
  while (sent < rgb.size()) {
    const ssize_t n = send(fd_, rgb.data() + sent, rgb.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw std::runtime_error("video: ffmpeg stopped reading frames (" + std::string(std::strerror(errno)) +
                               "); its messages: " + log_.string());
    sent += std::size_t(n);
  }
}

void VideoWriter::finish() {
  if (fd_ >= 0) close(fd_), fd_ = -1;
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = -1;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
    throw std::runtime_error("video: ffmpeg failed encoding " + out_.string() + "; its messages: " + log_.string());
  }
  std::filesystem::rename(tmp_, out_);
}

}  // namespace cellbake
