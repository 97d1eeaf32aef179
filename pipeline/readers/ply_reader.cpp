// Stanford PLY reader (Turk 1994): ASCII and binary of either byte order, any
// element order and scalar types. The vertex element is kept in memory
// (positions as double, optional colours and texcoords); the face element is
// streamed, each polygon triangulated as a fan without storing it. All other
// elements and properties are skipped.
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/buffered_input.h"
#include "pipeline/readers/colour_math.h"
#include "pipeline/readers/format_readers.h"
#include "pipeline/readers/ply_header.h"
#include "pipeline/readers/text_scan.h"

namespace cellbake {
namespace {

template <class T>
T load_value(const char* p, bool swap) {
  if constexpr (sizeof(T) == 1) {
    T value;
    std::memcpy(&value, p, 1);
    return value;
  } else {
    using Bits = std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                    std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
    Bits bits;
    std::memcpy(&bits, p, sizeof bits);
    if (swap) {
      if constexpr (sizeof(T) == 2) bits = __builtin_bswap16(bits);
      if constexpr (sizeof(T) == 4) bits = __builtin_bswap32(bits);
      if constexpr (sizeof(T) == 8) bits = __builtin_bswap64(bits);
    }
    return std::bit_cast<T>(bits);
  }
}

inline double decode_double(const char* p, PlyType type, bool swap) {
  switch (type) {
    case PlyType::int8:
      return load_value<std::int8_t>(p, swap);
    case PlyType::uint8:
      return load_value<std::uint8_t>(p, swap);
    case PlyType::int16:
      return load_value<std::int16_t>(p, swap);
    case PlyType::uint16:
      return load_value<std::uint16_t>(p, swap);
    case PlyType::int32:
      return load_value<std::int32_t>(p, swap);
    case PlyType::uint32:
      return load_value<std::uint32_t>(p, swap);
    case PlyType::float32:
      return load_value<float>(p, swap);
    case PlyType::float64:
      return load_value<double>(p, swap);
  }
  return 0;
}

inline std::int64_t decode_integer(const char* p, PlyType type, bool swap) {
  switch (type) {
    case PlyType::int8:
      return load_value<std::int8_t>(p, swap);
    case PlyType::uint8:
      return load_value<std::uint8_t>(p, swap);
    case PlyType::int16:
      return load_value<std::int16_t>(p, swap);
    case PlyType::uint16:
      return load_value<std::uint16_t>(p, swap);
    case PlyType::int32:
      return load_value<std::int32_t>(p, swap);
    case PlyType::uint32:
      return load_value<std::uint32_t>(p, swap);
    case PlyType::float32:
    case PlyType::float64: {
      const double value = decode_double(p, type, swap);
      if (!(std::abs(value) < 9e18)) return std::numeric_limits<std::int64_t>::min();
      return static_cast<std::int64_t>(value);
    }
  }
  return 0;
}

// Values of a binary body. Every read throws InputError with the byte offset
// when the file ends early.
class BinarySource {
 public:
  BinarySource(BufferedInput& in, bool big_endian)
      : in_(in), swap_(big_endian != (std::endian::native == std::endian::big)) {}

  // A cheap mark of the current place, turned into text only for messages.
  std::uint64_t position() const { return in_.offset(); }
  static std::string describe(std::uint64_t position) { return at_byte(position); }
  double real(PlyType type) {
    const std::size_t size = ply_type_size(type);
    const double value = decode_double(need(size), type, swap_);
    in_.consume(size);
    return value;
  }
  std::int64_t integer(PlyType type) {
    const std::size_t size = ply_type_size(type);
    const std::int64_t value = decode_integer(need(size), type, swap_);
    in_.consume(size);
    return value;
  }
  void skip(PlyType type, std::uint64_t count) {
    const std::uint64_t size = ply_type_size(type);
    if (count > std::numeric_limits<std::uint64_t>::max() / size || !in_.skip(count * size)) truncated();
  }
  // Calls visit(value, position) for `count` integers of `type`, decoding them
  // from whole blocks of the buffer rather than one fetch per item.
  template <class Visit>
  void integers(PlyType type, std::uint64_t count, Visit&& visit) {
    constexpr std::uint64_t kBlockItems = 1 << 16;
    const std::size_t size = ply_type_size(type);
    while (count > 0) {
      const std::size_t items = static_cast<std::size_t>(std::min(count, kBlockItems));
      const std::uint64_t start = in_.offset();
      const char* p = need(items * size);
      for (std::size_t i = 0; i < items; ++i)
        visit(decode_integer(p + i * size, type, swap_), start + i * size);
      in_.consume(items * size);
      count -= items;
    }
  }
  // The next `size` bytes, to be decoded by the caller and then consumed.
  const char* record(std::size_t size) { return need(size); }
  void consume(std::size_t size) { in_.consume(size); }
  bool swapped() const { return swap_; }
  const std::string& name() const { return in_.name(); }

 private:
  const char* need(std::size_t size) {
    const char* p = in_.fetch(size);
    if (!p) truncated();
    return p;
  }
  [[noreturn]] void truncated() const {
    throw InputError(in_.name(), describe(position()), "unexpected end of file" + context_);
  }

 public:
  // Binary records have no lines to check.
  void end_record(const PlyElement&, std::uint64_t, std::uint64_t) const {}

 private:
  BufferedInput& in_;
  bool swap_;

 public:
  // Names the element being read in end-of-file errors (ply_element_context).
  void set_context(std::string context) { context_ = std::move(context); }

 private:
  std::string context_;
};

// Values of an ASCII body: blank-separated tokens across lines. Every read
// throws InputError with the line number on a malformed token or early end.
class AsciiSource {
 public:
  explicit AsciiSource(BufferedInput& in) : in_(in), scan_(std::string_view()) {}

  // The line of the next token (moving to it first), or the last line at the end.
  std::uint64_t position() {
    advance();
    return in_.line_number();
  }
  static std::string describe(std::uint64_t position) { return at_line(position); }
  double real(PlyType) {
    next_token();
    double value;
    if (!scan_.number(value)) fail("malformed number");
    return value;
  }
  std::int64_t integer(PlyType type) {
    next_token();
    std::int64_t value;
    if (scan_.integer(value)) return value;
    double real_value;
    if (ply_type_is_float(type) && scan_.number(real_value) && std::abs(real_value) < 9e18)
      return static_cast<std::int64_t>(real_value);
    fail("malformed integer");
  }
  void skip(PlyType, std::uint64_t count) {
    for (std::uint64_t i = 0; i < count; ++i) {
      next_token();
      scan_.token();
    }
  }
  template <class Visit>
  void integers(PlyType type, std::uint64_t count, Visit&& visit) {
    for (std::uint64_t i = 0; i < count; ++i) {
      const std::uint64_t line = position();
      visit(integer(type), line);
    }
  }
  const std::string& name() const { return in_.name(); }
  // An ASCII record is one line: a record that began on line `start` and
  // needed tokens from a later one had too few values on its own line.
  void end_record(const PlyElement& element, std::uint64_t index, std::uint64_t start) const {
    if (in_.line_number() != start)
      throw InputError(in_.name(), describe(start),
                       element.name + " " + std::to_string(index) +
                           ": fewer values on the line than the element's " +
                           std::to_string(element.properties.size()) + " properties");
  }

 private:
  // Moves to the line holding the next token; false at the end of the input.
  bool advance() {
    while (scan_.at_end()) {
      std::string_view line;
      if (!in_.next_line(line)) return false;
      scan_ = TextScan(line);
    }
    return true;
  }
  void next_token() {
    if (!advance()) fail("unexpected end of file" + context_);
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(in_.name(), describe(in_.line_number()), what);
  }

  BufferedInput& in_;
  TextScan scan_;
  std::string context_;

 public:
  // Names the element being read in end-of-file errors (ply_element_context).
  void set_context(std::string context) { context_ = std::move(context); }
};

// What a vertex property feeds.
enum class VertexRole : std::uint8_t { none, x, y, z, red, green, blue, alpha, u, v, nx, ny, nz };

VertexRole vertex_role(const std::string& name) {
  if (name == "x") return VertexRole::x;
  if (name == "y") return VertexRole::y;
  if (name == "z") return VertexRole::z;
  if (name == "red" || name == "r" || name == "diffuse_red") return VertexRole::red;
  if (name == "green" || name == "g" || name == "diffuse_green") return VertexRole::green;
  if (name == "blue" || name == "b" || name == "diffuse_blue") return VertexRole::blue;
  if (name == "alpha" || name == "a" || name == "diffuse_alpha") return VertexRole::alpha;
  if (name == "s" || name == "u" || name == "texture_u" || name == "texture_s") return VertexRole::u;
  if (name == "t" || name == "v" || name == "texture_v" || name == "texture_t") return VertexRole::v;
  if (name == "nx") return VertexRole::nx;
  if (name == "ny") return VertexRole::ny;
  if (name == "nz") return VertexRole::nz;
  return VertexRole::none;
}

// A colour channel value to 8 bits: floats are 0..1, 16-bit integers 0..65535,
// other integers 0..255.
inline std::uint8_t colour_byte(double value, PlyType type) {
  if (ply_type_is_float(type)) return unit_to_byte(value);
  if (type == PlyType::uint16 || type == PlyType::int16) return unit_to_byte(value / 65535.0);
  return static_cast<std::uint8_t>(std::clamp(value, 0.0, 255.0));
}

// " in element vertex (count 99999999999999, line 3)": where an end of file
// was met, so a count the file cannot hold is named with its header line.
std::string ply_element_context(const PlyElement& element) {
  return " in element " + element.name + " (count " + std::to_string(element.count) + ", " +
         at_line(element.line) + ")";
}

struct VertexTable {
  std::vector<Vec3d> positions;
  std::vector<Rgba8> colours;  // empty or one per vertex
  std::vector<Uv> uvs;         // empty or one per vertex
  std::vector<Vec3f> normals;  // empty or one per vertex
};

class PlyReader {
 public:
  PlyReader(const std::filesystem::path& file, const TriangleCallback& emit) : file_(file), emit_(emit) {
    info_.format = "ply";
    info_.materials.push_back(default_material());
  }

  ModelInfo run() {
    BufferedInput in(file_);
    const PlyHeader header = read_ply_header(in);
    info_.warnings.insert(info_.warnings.end(), header.warnings.begin(), header.warnings.end());
    std::optional<std::size_t> vertex_element, face_element;
    for (std::size_t e = 0; e < header.elements.size(); ++e) {
      if (header.elements[e].name == "vertex" && !vertex_element) vertex_element = e;
      if (header.elements[e].name == "face" && !face_element) face_element = e;
    }
    if (!face_element || header.elements[*face_element].count == 0) return std::move(info_);
    if (!vertex_element) throw InputError(in.name(), "", "PLY has faces but no vertex element");
    index_property_ = find_index_property(in, header.elements[*face_element]);

    const bool faces_first = *face_element < *vertex_element;
    body(in, header, *vertex_element, faces_first ? std::nullopt : face_element);
    if (faces_first) {
      // Faces precede vertices: read the file again rather than hold the faces.
      BufferedInput again(file_);
      read_ply_header(again);
      body(again, header, std::nullopt, face_element);
    }
    // PLY has no material colours: vertex colours are the colour, even all equal.
    record_vertex_colour_use(info_, colour_variation(vertices_.colours), false);
    return std::move(info_);
  }

 private:
  std::size_t find_index_property(const BufferedInput& in, const PlyElement& face) const {
    for (std::size_t p = 0; p < face.properties.size(); ++p) {
      const PlyProperty& property = face.properties[p];
      if (property.is_list && (property.name == "vertex_indices" || property.name == "vertex_index"))
        return p;
    }
    throw InputError(in.name(), "", "PLY face element has no 'vertex_indices' list property");
  }

  // Walks the elements in order through the last one wanted: loads the vertex
  // element if asked, streams the face element if asked, skips the others.
  void body(BufferedInput& in, const PlyHeader& header, std::optional<std::size_t> vertices,
            std::optional<std::size_t> faces) {
    if (header.format == PlyFormat::ascii) {
      AsciiSource source(in);
      walk(source, in, header, vertices, faces);
    } else {
      BinarySource source(in, header.format == PlyFormat::binary_big_endian);
      walk(source, in, header, vertices, faces);
    }
  }

  template <class Source>
  void walk(Source& source, BufferedInput& in, const PlyHeader& header, std::optional<std::size_t> vertices,
            std::optional<std::size_t> faces) {
    const std::size_t last = std::max(vertices.value_or(0), faces.value_or(0));
    for (std::size_t e = 0; e <= last; ++e) {
      const PlyElement& element = header.elements[e];
      source.set_context(ply_element_context(element));
      if (e == vertices) {
        read_vertices(source, in, element);
      } else if (e == faces) {
        stream_faces(source, element);
      } else {
        for (std::uint64_t i = 0; i < element.count; ++i) skip_record(source, element);
      }
    }
  }

  template <class Source>
  static void skip_record(Source& source, const PlyElement& element) {
    for (const PlyProperty& property : element.properties) {
      if (property.is_list) {
        source.skip(property.type, list_count(source, property));
      } else {
        source.skip(property.type, 1);
      }
    }
  }

  template <class Source>
  static std::uint64_t list_count(Source& source, const PlyProperty& property) {
    const std::uint64_t position = source.position();
    const std::int64_t count = source.integer(property.count_type);
    if (count < 0)
      throw InputError(source.name(), Source::describe(position),
                       "negative list count " + std::to_string(count) + " in '" + property.name + "'");
    return static_cast<std::uint64_t>(count);
  }

  template <class Source>
  void read_vertices(Source& source, BufferedInput& in, const PlyElement& element) {
    std::vector<VertexRole> roles;
    bool has_x = false, has_y = false, has_z = false, has_colour = false, has_u = false, has_v = false;
    int normal_axes = 0;
    for (const PlyProperty& property : element.properties) {
      const VertexRole role = property.is_list ? VertexRole::none : vertex_role(property.name);
      roles.push_back(role);
      has_x |= role == VertexRole::x;
      has_y |= role == VertexRole::y;
      has_z |= role == VertexRole::z;
      has_colour |= role == VertexRole::red || role == VertexRole::green || role == VertexRole::blue;
      has_u |= role == VertexRole::u;
      has_v |= role == VertexRole::v;
      normal_axes += role == VertexRole::nx || role == VertexRole::ny || role == VertexRole::nz;
    }
    has_normals_ = normal_axes == 3;
    if (!has_x || !has_y || !has_z) throw InputError(in.name(), "", "PLY vertex element lacks x, y or z");
    const bool has_uv = has_u && has_v;

    // Reserve no more than the file could hold, so a lying count cannot exhaust memory.
    std::uint64_t reserve = std::min<std::uint64_t>(element.count, std::uint64_t{1} << 24);
    if (in.plain_size()) reserve = std::min<std::uint64_t>(element.count, *in.plain_size() / 3);
    vertices_.positions.reserve(reserve);
    if (has_colour) vertices_.colours.reserve(reserve);
    if (has_uv) vertices_.uvs.reserve(reserve);
    if (has_normals_) vertices_.normals.reserve(reserve);

    if constexpr (std::is_same_v<Source, BinarySource>) {
      if (!element.has_lists()) return read_fixed_vertices(source, in, element, roles, has_colour, has_uv);
    }
    for (std::uint64_t i = 0; i < element.count; ++i) {
      const std::uint64_t start = source.position();
      VertexValues values;
      for (std::size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        if (property.is_list) {
          source.skip(property.type, list_count(source, property));
        } else if (roles[k] == VertexRole::none) {
          source.skip(property.type, 1);
        } else {
          values.assign(roles[k], source.real(property.type), property.type);
        }
      }
      source.end_record(element, i, start);
      store_vertex<Source>(values, has_colour, has_uv, in.name(), start, i);
    }
  }

  // Binary vertices without list properties: one fetch per record, fields
  // decoded at fixed offsets.
  void read_fixed_vertices(BinarySource& source, BufferedInput& in, const PlyElement& element,
                           const std::vector<VertexRole>& roles, bool has_colour, bool has_uv) {
    struct Field {
      VertexRole role;
      PlyType type;
      std::size_t offset;
    };
    std::vector<Field> fields;
    std::size_t offset = 0;
    for (std::size_t k = 0; k < element.properties.size(); ++k) {
      if (roles[k] != VertexRole::none) fields.push_back({roles[k], element.properties[k].type, offset});
      offset += ply_type_size(element.properties[k].type);
    }
    const std::size_t record_size = offset;
    for (std::uint64_t i = 0; i < element.count; ++i) {
      const std::uint64_t start = source.position();
      const char* record = source.record(record_size);
      VertexValues values;
      for (const Field& field : fields)
        values.assign(field.role, decode_double(record + field.offset, field.type, source.swapped()),
                      field.type);
      source.consume(record_size);
      store_vertex<BinarySource>(values, has_colour, has_uv, in.name(), start, i);
    }
  }

  // One vertex's values as they are decoded.
  struct VertexValues {
    Vec3d p;
    Rgba8 colour{0, 0, 0, 255};
    Uv uv;
    Vec3f n;
    void assign(VertexRole role, double value, PlyType type) {
      switch (role) {
        case VertexRole::x:
          p.x = value;
          break;
        case VertexRole::y:
          p.y = value;
          break;
        case VertexRole::z:
          p.z = value;
          break;
        case VertexRole::red:
          colour.r = colour_byte(value, type);
          break;
        case VertexRole::green:
          colour.g = colour_byte(value, type);
          break;
        case VertexRole::blue:
          colour.b = colour_byte(value, type);
          break;
        case VertexRole::alpha:
          colour.a = colour_byte(value, type);
          break;
        case VertexRole::u:
          uv.u = static_cast<float>(value);
          break;
        case VertexRole::v:
          uv.v = static_cast<float>(value);
          break;
        case VertexRole::nx:
          n.x = static_cast<float>(value);
          break;
        case VertexRole::ny:
          n.y = static_cast<float>(value);
          break;
        case VertexRole::nz:
          n.z = static_cast<float>(value);
          break;
        case VertexRole::none:
          break;
      }
    }
  };

  template <class Source>
  void store_vertex(const VertexValues& values, bool has_colour, bool has_uv, const std::string& name,
                    std::uint64_t position, std::uint64_t index) {
    if (!is_finite(values.p))
      throw InputError(name, Source::describe(position),
                       "non-finite coordinate in vertex " + std::to_string(index));
    vertices_.positions.push_back(values.p);
    if (has_colour) vertices_.colours.push_back(values.colour);
    if (has_uv) vertices_.uvs.push_back(values.uv);
    if (has_normals_) vertices_.normals.push_back(values.n);
  }

  template <class Source>
  void stream_faces(Source& source, const PlyElement& element) {
    const std::uint64_t vertex_count = vertices_.positions.size();
    for (std::uint64_t f = 0; f < element.count; ++f) {
      for (std::size_t k = 0; k < element.properties.size(); ++k) {
        const PlyProperty& property = element.properties[k];
        if (k != index_property_) {
          if (property.is_list) {
            source.skip(property.type, list_count(source, property));
          } else {
            source.skip(property.type, 1);
          }
          continue;
        }
        const std::uint64_t face_start = source.position();
        const std::uint64_t corners = list_count(source, property);
        if (corners < 3)
          throw InputError(source.name(), Source::describe(face_start),
                           "face " + std::to_string(f) + " has " + std::to_string(corners) + " vertices");
        std::uint64_t first = 0, previous = 0, c = 0;
        source.integers(property.type, corners, [&](std::int64_t index, std::uint64_t position) {
          if (index < 0 || static_cast<std::uint64_t>(index) >= vertex_count)
            throw InputError(source.name(), Source::describe(position),
                             "face " + std::to_string(f) + " vertex index " + std::to_string(index) +
                                 " out of range (" + std::to_string(vertex_count) + " vertices)");
          const auto current = static_cast<std::uint64_t>(index);
          if (c == 0) first = current;
          if (c >= 2) emit_triangle(first, previous, current);
          previous = current;
          ++c;
        });
        if (corners > 3) ++info_.polygons_triangulated;
      }
    }
  }

  void emit_triangle(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
    Triangle t;
    const std::uint64_t corners[3] = {a, b, c};
    const Rgba8 grey = info_.materials[0].color;
    for (int i = 0; i < 3; ++i) {
      t.p[i] = vertices_.positions[corners[i]];
      t.color[i] = vertices_.colours.empty() ? grey : vertices_.colours[corners[i]];
      if (!vertices_.uvs.empty()) t.uv[i] = vertices_.uvs[corners[i]];
      if (!vertices_.normals.empty()) t.normal[i] = vertices_.normals[corners[i]];
    }
    t.has_normals = !vertices_.normals.empty();
    emit_(t);
    ++info_.triangles_emitted;
  }

  std::filesystem::path file_;
  const TriangleCallback& emit_;
  ModelInfo info_;
  VertexTable vertices_;
  std::size_t index_property_ = 0;
  bool has_normals_ = false;  // the vertex element has nx, ny and nz
};

}  // namespace

ModelInfo read_ply(const std::filesystem::path& file, const TriangleCallback& emit) {
  return PlyReader(file, emit).run();
}

}  // namespace cellbake
