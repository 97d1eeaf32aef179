#include "stages/encode/encode_triangle_list.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "stages/little_endian.h"

namespace cellbake {
namespace {

constexpr std::uint32_t kMagic = 0x4C544243;  // "CBTL" little-endian
constexpr std::uint8_t kVersion = 1;
constexpr std::size_t kHeader = 5;

void put_varint(std::vector<std::uint8_t>& out, std::uint32_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

class VarintReader {
 public:
  explicit VarintReader(std::span<const std::uint8_t> data) : data_(data) {}
  std::uint32_t next(const char* what) {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 35; shift += 7) {
      if (pos_ == data_.size()) throw std::runtime_error(std::string("triangle list: truncated in ") + what);
      const std::uint8_t b = data_[pos_++];
      v |= std::uint64_t(b & 0x7f) << shift;
      if (!(b & 0x80)) {
        if (v > kMaxTriangleListIndex) throw std::runtime_error(std::string("triangle list: ") + what + " out of range");
        return static_cast<std::uint32_t>(v);
      }
    }
    throw std::runtime_error(std::string("triangle list: overlong varint in ") + what);
  }
  bool at_end() const { return pos_ == data_.size(); }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
};

}  // namespace

std::vector<std::uint8_t> encode_triangle_list(std::span<const std::uint32_t> triangles) {
  std::vector<std::uint8_t> out(kHeader);
  little_endian::put_u32(out.data(), kMagic);
  out[4] = kVersion;
  put_varint(out, static_cast<std::uint32_t>(triangles.size()));
  std::uint32_t end = 0;  // one past the previous run
  std::size_t k = 0;
  while (k < triangles.size()) {
    const std::uint32_t first = triangles[k];
    if (first >= kMaxTriangleListIndex || (k > 0 && first < end))
      throw std::invalid_argument("encode_triangle_list: triangle numbers not ascending or out of range");
    std::size_t j = k + 1;
    while (j < triangles.size() && triangles[j] == triangles[j - 1] + 1) ++j;
    if (triangles[j - 1] >= kMaxTriangleListIndex)
      throw std::invalid_argument("encode_triangle_list: triangle number out of range");
    put_varint(out, first - end);
    put_varint(out, static_cast<std::uint32_t>(j - k));
    end = triangles[j - 1] + 1;
    k = j;
  }
  return out;
}

bool is_triangle_list_blob(std::span<const std::uint8_t> data) {
  return data.size() >= kHeader && little_endian::get_u32(data.data()) == kMagic;
}

std::vector<std::uint32_t> decode_triangle_list(std::span<const std::uint8_t> data) {
  if (!is_triangle_list_blob(data)) throw std::runtime_error("triangle list: bad magic");
  if (data[4] != kVersion) throw std::runtime_error("triangle list: unknown version " + std::to_string(data[4]));
  VarintReader in(data.subspan(kHeader));
  const std::uint32_t count = in.next("count");
  std::vector<std::uint32_t> triangles;
  triangles.reserve(std::min<std::uint32_t>(count, 1u << 16));  // the count is untrusted
  std::uint64_t end = 0;
  while (triangles.size() < count) {
    const std::uint64_t first = end + in.next("gap");
    const std::uint32_t length = in.next("run length");
    if (length == 0) throw std::runtime_error("triangle list: empty run");
    if (triangles.size() + length > count) throw std::runtime_error("triangle list: runs exceed the count");
    if (first + length > kMaxTriangleListIndex) throw std::runtime_error("triangle list: triangle number out of range");
    for (std::uint32_t i = 0; i < length; ++i) triangles.push_back(static_cast<std::uint32_t>(first + i));
    end = first + length;
  }
  if (!in.at_end()) throw std::runtime_error("triangle list: trailing bytes");
  return triangles;
}

}  // namespace cellbake
