// MP4 output of a walk through the `ffmpeg` program (Debian package ffmpeg):
// raw RGB frames are streamed to its standard input, it encodes H.264
// (libx264; MPEG-4 part 2 when its build lacks x264) into a temporary file
// renamed over the target when it succeeds, so a reader never sees half a video.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cellbake {

// The ffmpeg executable on $PATH, if any.
std::optional<std::filesystem::path> find_ffmpeg();

class VideoWriter {
 public:
  // Starts `ffmpeg` encoding width x height RGB frames (3 bytes per pixel,
  // row 0 at the top) at `fps` into `out` (odd sizes are padded by one
  // black row/column). Its messages go to `log`. Throws std::runtime_error
  // naming the program when it cannot be started.
  VideoWriter(const std::filesystem::path& ffmpeg, const std::filesystem::path& out, int width, int height,
              double fps, const std::filesystem::path& log);
  ~VideoWriter();  // an unfinished video: ffmpeg is stopped, the temporary removed
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // Sends one frame (width * height * 3 bytes). Throws std::runtime_error
  // (naming the log) when ffmpeg has stopped reading or the size is wrong.
  void write(const std::vector<unsigned char>& rgb);
  // Ends the stream, waits for ffmpeg and renames the result to `out`.
  // Throws std::runtime_error naming the log when ffmpeg failed.
  void finish();
  // "libx264" or "mpeg4": what encodes the video.
  const std::string& codec() const { return codec_; }

 private:
  void stop();
  std::filesystem::path out_, tmp_, log_;
  int width_, height_;
  int fd_ = -1;
  pid_t pid_ = -1;
  std::string codec_;
};

}  // namespace cellbake
