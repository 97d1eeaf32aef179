// STL reader, ASCII and binary, fully streamed. A file that starts with
// "solid" is still binary when its size is exactly 84 + 50 n bytes for the
// triangle count n in its header (many exporters write "solid" into the binary
// header); for gzip input, whose size is unknown up front, the first kilobyte
// is checked for the "facet"/"endsolid" keywords instead. STL has no colour
// standard, so every triangle gets the default material colour.
#include <array>
#include <cstdint>
#include <cstring>
#include <string>

#include "pipeline/input_error.h"
#include "pipeline/readers/buffered_input.h"
#include "pipeline/readers/format_readers.h"
#include "pipeline/readers/text_scan.h"

namespace cellbake {
namespace {

constexpr std::size_t kBinaryHeader = 84;
constexpr std::size_t kBinaryRecord = 50;

std::uint32_t load_u32_le(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 |
         std::uint32_t{b[3]} << 24;
}

float load_f32_le(const char* p) {
  const std::uint32_t bits = load_u32_le(p);
  float value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

bool starts_with_solid(const char* p, std::size_t n) {
  std::size_t i = 0;
  while (i < n && (is_blank(p[i]) || p[i] == '\n')) ++i;
  return n - i >= 5 && std::memcmp(p + i, "solid", 5) == 0;
}

bool looks_binary(BufferedInput& in) {
  const char* head = in.fetch(kBinaryHeader);
  if (!head) return false;  // shorter than any binary STL: only ASCII can be valid
  if (!starts_with_solid(head, kBinaryHeader)) return true;
  const std::uint64_t triangles = load_u32_le(head + 80);
  if (in.plain_size()) return *in.plain_size() == kBinaryHeader + kBinaryRecord * triangles;
  std::size_t available = 1024;
  const char* window = in.fetch(available);
  if (!window) {
    available = in.buffered();
    window = in.fetch(available);
  }
  const std::string_view text(window, available);
  return text.find("facet") == std::string_view::npos && text.find("endsolid") == std::string_view::npos;
}

class StlReader {
 public:
  StlReader(const std::filesystem::path& file, const TriangleCallback& emit) : in_(file), emit_(emit) {
    info_.format = "stl";
    info_.materials.push_back(default_material());
    triangle_.color = {info_.materials[0].color, info_.materials[0].color, info_.materials[0].color};
  }

  ModelInfo run() {
    if (looks_binary(in_)) {
      read_binary();
    } else {
      read_ascii();
    }
    return std::move(info_);
  }

 private:
  void read_binary() {
    const char* head = in_.fetch(kBinaryHeader);
    const std::uint64_t triangles = load_u32_le(head + 80);
    in_.consume(kBinaryHeader);
    if (in_.plain_size() && *in_.plain_size() < kBinaryHeader + kBinaryRecord * triangles)
      throw InputError(in_.name(), at_byte(80),
                       "binary STL header announces " + std::to_string(triangles) +
                           " triangles but the file has only " + std::to_string(*in_.plain_size()) +
                           " bytes");
    for (std::uint64_t i = 0; i < triangles; ++i) {
      const char* record = in_.fetch(kBinaryRecord);
      if (!record)
        throw InputError(in_.name(), at_byte(in_.offset()),
                         "unexpected end of file in triangle " + std::to_string(i));
      for (int corner = 0; corner < 3; ++corner) {
        const char* v = record + 12 + 12 * corner;
        triangle_.p[corner] = {load_f32_le(v), load_f32_le(v + 4), load_f32_le(v + 8)};
      }
      if (!is_finite(triangle_.p[0]) || !is_finite(triangle_.p[1]) || !is_finite(triangle_.p[2]))
        throw InputError(in_.name(), at_byte(in_.offset()),
                         "non-finite coordinate in triangle " + std::to_string(i));
      in_.consume(kBinaryRecord);
      emit_(triangle_);
      ++info_.triangles_emitted;
    }
    // More records than the header announces: refuse rather than drop them silently.
    if (in_.fetch(1)) {
      std::uint64_t extra = 0;
      while (in_.fetch(1)) {
        const std::size_t n = in_.buffered();
        in_.consume(n);
        extra += n;
      }
      throw InputError(in_.name(), at_byte(80),
                       "binary STL header announces " + std::to_string(triangles) + " triangles (" +
                           std::to_string(kBinaryHeader + kBinaryRecord * triangles) + " bytes) but the file has " +
                           std::to_string(in_.offset()) + " bytes (" +
                           std::to_string(triangles + extra / kBinaryRecord) + " whole triangle records)");
    }
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(in_.name(), at_line(in_.line_number()), what);
  }

  // solid / facet normal / outer loop / vertex x3+ / endloop / endfacet / endsolid.
  // A loop with more than three vertices is split into a fan.
  void read_ascii() {
    std::string_view line;
    bool in_loop = false;
    int corners = 0;
    Vec3d first, previous;
    while (in_.next_line(line)) {
      TextScan scan(line);
      const std::string_view key = scan.token();
      if (key == "vertex") {
        if (!in_loop) fail("'vertex' outside 'outer loop'");
        Vec3d p;
        if (!scan.number(p.x) || !scan.number(p.y) || !scan.number(p.z) || !scan.at_end())
          fail("malformed vertex (expected 'vertex x y z')");
        if (!is_finite(p)) fail("non-finite coordinate");
        if (corners == 0) first = p;
        if (corners >= 2) emit({first, previous, p});
        previous = p;
        ++corners;
      } else if (key == "outer") {
        if (in_loop) fail("nested 'outer loop'");
        in_loop = true;
        corners = 0;
      } else if (key == "endloop") {
        if (!in_loop) fail("'endloop' without 'outer loop'");
        if (corners < 3) fail("facet with " + std::to_string(corners) + " vertices");
        if (corners > 3) ++info_.polygons_triangulated;
        in_loop = false;
      } else if (key.empty() || key == "solid" || key == "endsolid" || key == "facet" || key == "endfacet") {
        continue;
      } else {
        fail("unexpected '" + std::string(key) + "' in ASCII STL");
      }
    }
    if (in_loop) fail("unexpected end of file inside 'outer loop'");
  }

  void emit(const std::array<Vec3d, 3>& p) {
    triangle_.p = p;
    emit_(triangle_);
    ++info_.triangles_emitted;
  }

  BufferedInput in_;
  const TriangleCallback& emit_;
  ModelInfo info_;
  Triangle triangle_;
};

}  // namespace

ModelInfo read_stl(const std::filesystem::path& file, const TriangleCallback& emit) {
  return StlReader(file, emit).run();
}

}  // namespace cellbake
