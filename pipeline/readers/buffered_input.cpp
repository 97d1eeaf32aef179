#include "pipeline/readers/buffered_input.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "pipeline/input_error.h"

namespace cellbake {
namespace {

constexpr std::size_t kInitialBuffer = std::size_t{1} << 20;
constexpr std::size_t kMaxBuffer = std::size_t{256} << 20;

bool has_gz_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".gz";
}

}  // namespace

BufferedInput::BufferedInput(const std::filesystem::path& file) : name_(file.string()), buf_(kInitialBuffer) {
  std::error_code ec;
  require_regular_file(file);
  if (has_gz_extension(file)) {
    gz_ = gzopen(name_.c_str(), "rb");
    if (!gz_) throw InputError(name_, "", std::string("cannot open: ") + std::strerror(errno));
    gzbuffer(gz_, 1u << 18);
    const auto compressed = std::filesystem::file_size(file, ec);
    gzip_limit_ = std::max(kGzipFloorBytes, ec ? 0 : compressed * kMaxGzipRatio);
  } else {
    plain_ = std::fopen(name_.c_str(), "rb");
    if (!plain_) throw InputError(name_, "", std::string("cannot open: ") + std::strerror(errno));
    std::setvbuf(plain_, nullptr, _IONBF, 0);
    const auto size = std::filesystem::file_size(file, ec);
    if (!ec) plain_size_ = size;
  }
}

BufferedInput::~BufferedInput() {
  if (plain_) std::fclose(plain_);
  if (gz_) gzclose(gz_);
}

std::size_t BufferedInput::read_raw(char* dst, std::size_t n) {
  if (plain_) {
    const std::size_t got = std::fread(dst, 1, n, plain_);
    if (got < n && std::ferror(plain_))
      throw InputError(name_, at_byte(offset_ + buffered()),
                       std::string("read error: ") + std::strerror(errno));
    return got;
  }
  const unsigned chunk = static_cast<unsigned>(std::min<std::size_t>(n, std::size_t{1} << 30));
  const int got = gzread(gz_, dst, chunk);
  if (got < 0) {
    int code = 0;
    const char* message = gzerror(gz_, &code);
    throw InputError(name_, at_byte(offset_ + buffered()), std::string("gzip error: ") + message);
  }
  if (got == 0) {
    int code = Z_OK;
    gzerror(gz_, &code);
    if (code == Z_BUF_ERROR)  // zlib's report of a compressed stream cut short
      throw InputError(name_, at_byte(offset_ + buffered()),
                       "gzip error: compressed data ends early (truncated file)");
  }
  decompressed_ += static_cast<std::uint64_t>(got);
  if (decompressed_ > gzip_limit_)
    throw InputError(name_, at_byte(offset_ + buffered()),
                     "gzip data decompresses to more than " + std::to_string(gzip_limit_) +
                         " bytes (the larger of 64 MiB and " + std::to_string(kMaxGzipRatio) +
                         " times the compressed file): refused as a decompression bomb; a real model this "
                         "compressible can be decompressed first");
  return static_cast<std::size_t>(got);
}

std::size_t BufferedInput::refill() {
  if (eof_) return 0;
  if (begin_ > 0) {
    std::memmove(buf_.data(), buf_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (end_ == buf_.size()) {
    if (buf_.size() >= kMaxBuffer)
      throw InputError(name_, at_byte(offset_), "record or line longer than 256 MiB");
    buf_.resize(std::min(buf_.size() * 2, kMaxBuffer));
  }
  const std::size_t got = read_raw(buf_.data() + end_, buf_.size() - end_);
  if (got == 0) eof_ = true;
  end_ += got;
  return got;
}

const char* BufferedInput::fetch_slow(std::size_t n) {
  if (n > kMaxBuffer) return nullptr;
  while (end_ - begin_ < n) {
    if (begin_ == 0 && end_ == buf_.size() && buf_.size() < n) buf_.resize(std::max(n, buf_.size() * 2));
    if (refill() == 0) return nullptr;
  }
  return buf_.data() + begin_;
}

bool BufferedInput::skip(std::uint64_t n) {
  while (n > 0) {
    if (begin_ == end_ && refill() == 0) return false;
    const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(n, end_ - begin_));
    consume(step);
    n -= step;
  }
  return true;
}

bool BufferedInput::next_line(std::string_view& line) {
  std::size_t scanned = 0;  // bytes after begin_ already known to hold no '\n'
  for (;;) {
    const char* start = buf_.data() + begin_;
    const void* newline = std::memchr(start + scanned, '\n', end_ - begin_ - scanned);
    if (newline) {
      const std::size_t length = static_cast<const char*>(newline) - start;
      line = std::string_view(start, length);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      consume(length + 1);
      ++line_number_;
      return true;
    }
    scanned = end_ - begin_;
    if (refill() == 0) {
      if (begin_ == end_) return false;
      line = std::string_view(buf_.data() + begin_, end_ - begin_);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      consume(end_ - begin_);
      ++line_number_;
      return true;
    }
  }
}

void BufferedInput::read_rest(std::vector<char>& out) {
  do {
    out.insert(out.end(), buf_.data() + begin_, buf_.data() + end_);
    consume(end_ - begin_);
  } while (refill() > 0);
}

}  // namespace cellbake
