// Geomview OFF reader: "[ST][C][N]OFF" headers, vertex counts, then one vertex
// and one face per line; '#' starts a comment. Vertex colours (COFF) are
// either integers 0..255 or floats 0..1, with optional alpha. Faces are
// streamed as triangle fans; anything after a face's indices (a face colour)
// is ignored.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/buffered_input.h"
#include "pipeline/readers/colour_math.h"
#include "pipeline/readers/format_readers.h"
#include "pipeline/readers/text_scan.h"

namespace cellbake {
namespace {

struct OffLayout {
  bool texcoords = false;  // ST prefix
  bool colours = false;    // C prefix
  bool normals = false;    // N prefix
};

// Parses the header keyword; returns false if `word` is not one.
bool parse_keyword(std::string_view word, OffLayout& layout, bool& unsupported) {
  if (word.size() < 3 || word.substr(word.size() - 3) != "OFF") return false;
  std::string_view prefix = word.substr(0, word.size() - 3);
  if (prefix.starts_with("ST")) {
    layout.texcoords = true;
    prefix.remove_prefix(2);
  }
  if (prefix.starts_with("C")) {
    layout.colours = true;
    prefix.remove_prefix(1);
  }
  if (prefix.starts_with("N")) {
    layout.normals = true;
    prefix.remove_prefix(1);
  }
  unsupported = !prefix.empty();  // 4OFF / nOFF (higher dimensions)
  return true;
}

bool is_integer_token(std::string_view token) { return token.find_first_of(".eE") == std::string_view::npos; }

class OffReader {
 public:
  OffReader(const std::filesystem::path& file, const TriangleCallback& emit) : in_(file), emit_(emit) {
    info_.format = "off";
    info_.materials.push_back(default_material());
  }

  ModelInfo run() {
    std::string_view line;
    if (!next_significant(line)) return std::move(info_);  // an empty file holds no triangles
    TextScan scan(line);
    OffLayout layout;
    bool unsupported = false;
    const std::string_view first = scan.token();
    if (!parse_keyword(first, layout, unsupported))
      scan = TextScan(line);  // headerless OFF: counts come first
    if (unsupported) fail("unsupported OFF variant '" + std::string(first) + "' (only 3D is supported)");
    if (scan.at_end()) {
      if (!next_significant(line)) fail("missing vertex and face counts");
      scan = TextScan(line);
    }
    std::int64_t vertex_count = 0, face_count = 0;
    if (!scan.integer(vertex_count) || !scan.integer(face_count) || vertex_count < 0 || face_count < 0)
      fail("expected '<vertices> <faces> [<edges>]'");
    counts_ = " (vertex count " + std::to_string(vertex_count) + ", face count " +
              std::to_string(face_count) + ", " + at_line(in_.line_number()) + ")";

    read_vertices(static_cast<std::uint64_t>(vertex_count), layout);
    for (std::int64_t f = 0; f < face_count; ++f) {
      if (!next_significant(line)) fail("unexpected end of file in face " + std::to_string(f) + counts_);
      read_face(line);
    }
    // OFF has no material colours: vertex colours are the colour, even all equal.
    record_vertex_colour_use(info_, colour_variation(colours_), false);
    return std::move(info_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(in_.name(), at_line(in_.line_number()), what);
  }

  // Next line with something besides blanks and a '#' comment, comment removed.
  bool next_significant(std::string_view& line) {
    while (in_.next_line(line)) {
      const auto hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      if (!TextScan(line).at_end()) return true;
    }
    return false;
  }

  void read_vertices(std::uint64_t count, const OffLayout& layout) {
    positions_.reserve(std::min<std::uint64_t>(count, std::uint64_t{1} << 24));
    std::string_view line;
    for (std::uint64_t i = 0; i < count; ++i) {
      if (!next_significant(line)) fail("unexpected end of file in vertex " + std::to_string(i) + counts_);
      TextScan scan(line);
      Vec3d p;
      if (!scan.number(p.x) || !scan.number(p.y) || !scan.number(p.z)) fail("malformed vertex");
      if (!is_finite(p)) fail("non-finite coordinate");
      positions_.push_back(p);
      if (layout.normals) {
        double n;
        if (!scan.number(n) || !scan.number(n) || !scan.number(n)) fail("malformed vertex normal");
      }
      if (layout.colours) colours_.push_back(read_colour(scan, layout.texcoords));
      if (layout.texcoords) {
        double u, v;
        if (!scan.number(u) || !scan.number(v)) fail("malformed vertex texture coordinate");
        uvs_.push_back({static_cast<float>(u), static_cast<float>(v)});
      }
    }
  }

  // Three or four colour values; when texcoords follow, the last two tokens are not colour.
  Rgba8 read_colour(TextScan& scan, bool texcoords_follow) {
    std::string_view tokens[6];
    int count = 0;
    TextScan probe = scan;
    while (count < 6 && !probe.at_end()) tokens[count++] = probe.token();
    const int colour_values = count - (texcoords_follow ? 2 : 0);
    if (colour_values != 3 && colour_values != 4) fail("expected 3 or 4 colour values in COFF vertex");
    const bool bytes = std::all_of(tokens, tokens + colour_values, is_integer_token);
    double value[4] = {0, 0, 0, bytes ? 255.0 : 1.0};
    for (int k = 0; k < colour_values; ++k)
      if (!scan.number(value[k])) fail("malformed colour value");
    if (bytes) {
      return {static_cast<std::uint8_t>(std::clamp(value[0], 0.0, 255.0)),
              static_cast<std::uint8_t>(std::clamp(value[1], 0.0, 255.0)),
              static_cast<std::uint8_t>(std::clamp(value[2], 0.0, 255.0)),
              static_cast<std::uint8_t>(std::clamp(value[3], 0.0, 255.0))};
    }
    return {unit_to_byte(value[0]), unit_to_byte(value[1]), unit_to_byte(value[2]), unit_to_byte(value[3])};
  }

  void read_face(std::string_view line) {
    TextScan scan(line);
    std::int64_t corners;
    if (!scan.integer(corners)) fail("malformed face (expected '<n> <i0> ... <in-1>')");
    if (corners < 3) fail("face with " + std::to_string(corners) + " vertices");
    std::uint64_t first = 0, previous = 0;
    for (std::int64_t c = 0; c < corners; ++c) {
      std::int64_t index;
      if (!scan.integer(index)) fail("malformed or missing face index");
      if (index < 0 || static_cast<std::uint64_t>(index) >= positions_.size())
        fail("vertex index " + std::to_string(index) + " out of range (" + std::to_string(positions_.size()) +
             " vertices)");
      const auto current = static_cast<std::uint64_t>(index);
      if (c == 0) first = current;
      if (c >= 2) emit_triangle(first, previous, current);
      previous = current;
    }
    if (corners > 3) ++info_.polygons_triangulated;
  }

  void emit_triangle(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
    Triangle t;
    const std::uint64_t corners[3] = {a, b, c};
    const Rgba8 grey = info_.materials[0].color;
    for (int i = 0; i < 3; ++i) {
      t.p[i] = positions_[corners[i]];
      t.color[i] = colours_.empty() ? grey : colours_[corners[i]];
      if (!uvs_.empty()) t.uv[i] = uvs_[corners[i]];
    }
    emit_(t);
    ++info_.triangles_emitted;
  }

  BufferedInput in_;
  std::string counts_;  // " (vertex count V, face count F, line N)" for end-of-file errors
  const TriangleCallback& emit_;
  ModelInfo info_;
  std::vector<Vec3d> positions_;
  std::vector<Rgba8> colours_;  // empty or one per vertex
  std::vector<Uv> uvs_;         // empty or one per vertex
};

}  // namespace

ModelInfo read_off(const std::filesystem::path& file, const TriangleCallback& emit) {
  return OffReader(file, emit).run();
}

}  // namespace cellbake
