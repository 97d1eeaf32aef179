// Buffered sequential reader over a plain or gzip-compressed file, shared by the
// streaming model readers: lines for text formats, contiguous byte windows for
// binary formats, both from the same buffer so a text header can be followed by
// binary data. Memory is bounded by the buffer (1 MiB, grown only for a single
// longer line, up to 256 MiB). Gzip input may decompress to at most
// kMaxGzipRatio times its compressed size (and always to kGzipFloorBytes): a
// decompression bomb (4 GB of zeros in a 4 MB file) is refused before the
// tables a reader builds from it (PLY or OFF vertices) can exhaust memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

struct gzFile_s;

namespace cellbake {

// Model files compress about 2 to 10 times (binary floats less, ASCII more);
// zeros compress about 1000 times. The vertex table a reader holds is about
// twice the decompressed bytes (briefly three times while it grows), so a
// reader's memory stays within about 100 times the .gz file's size.
inline constexpr std::uint64_t kMaxGzipRatio = 32;
inline constexpr std::uint64_t kGzipFloorBytes = std::uint64_t{64} << 20;

class BufferedInput {
 public:
  // Opens `file`; a name ending in ".gz" (any case) is decompressed on the fly
  // with zlib. Throws InputError naming the file when it cannot be opened, and
  // while reading when gzip data decompresses to more than
  // max(kGzipFloorBytes, kMaxGzipRatio x the compressed file's size).
  explicit BufferedInput(const std::filesystem::path& file);
  ~BufferedInput();
  BufferedInput(const BufferedInput&) = delete;
  BufferedInput& operator=(const BufferedInput&) = delete;

  // The file name used in error messages.
  const std::string& name() const { return name_; }

  // Size in bytes of an uncompressed file; nullopt for gzip input.
  std::optional<std::uint64_t> plain_size() const { return plain_size_; }

  // Sets `line` to the next line without its "\n" / "\r\n" terminator and
  // returns true, or returns false at the end of input. The view stays valid
  // until the next call on this object.
  bool next_line(std::string_view& line);

  // 1-based number of the line last returned by next_line().
  std::uint64_t line_number() const { return line_number_; }

  // Returns a pointer to at least `n` contiguous unread bytes (not consumed),
  // or nullptr when the input ends first. Valid until the next call.
  const char* fetch(std::size_t n) {
    if (end_ - begin_ >= n) return buf_.data() + begin_;
    return fetch_slow(n);
  }

  // Marks `n` bytes (previously fetched) as read.
  void consume(std::size_t n) {
    begin_ += n;
    offset_ += n;
  }

  // Skips `n` bytes; returns false when the input ends first.
  bool skip(std::uint64_t n);

  // Unread bytes currently buffered (after a failed fetch: all that is left).
  std::size_t buffered() const { return end_ - begin_; }

  // Bytes consumed so far, counted in the decompressed stream.
  std::uint64_t offset() const { return offset_; }

  // Appends everything left in the input to `out` (for whole-file consumers).
  void read_rest(std::vector<char>& out);

 private:
  const char* fetch_slow(std::size_t n);
  // Moves unread bytes to the front and reads more; returns bytes added (0 at end).
  std::size_t refill();
  std::size_t read_raw(char* dst, std::size_t n);

  std::string name_;
  std::optional<std::uint64_t> plain_size_;
  std::uint64_t gzip_limit_ = 0;    // decompressed bytes a gzip file may yield
  std::uint64_t decompressed_ = 0;  // yielded so far
  std::FILE* plain_ = nullptr;
  gzFile_s* gz_ = nullptr;
  std::vector<char> buf_;
  std::size_t begin_ = 0, end_ = 0;
  bool eof_ = false;
  std::uint64_t offset_ = 0;
  std::uint64_t line_number_ = 0;
};

}  // namespace cellbake
