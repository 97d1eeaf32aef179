// Wavefront OBJ reader: one pass over the lines, faces triangulated as fans and
// emitted as soon as they are parsed. Supported statements: v (with optional
// "r g b [a]" vertex colour extension, floats 0..1), vt, vn, f, mtllib, usemtl;
// everything else (o, g, s, l, p, curves, ...) is ignored.
//
// Vertex colours multiply material colours only when they vary across the
// file; when every vertex colour is the same (exporters write "v x y z 0 0 0"
// or "1 1 1" by default), the material's Kd wins, so such a file is not
// blanked. Faces under the default material (before any usemtl, or naming an
// unknown material) keep their vertex colours either way. The decision is
// file-wide: at the first face that needs it, unless the colours read so far
// already vary, a second streaming pass over the file's "v" lines settles it
// (stopping at the first differing colour), so faces are still emitted as
// they are parsed.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/buffered_input.h"
#include "pipeline/readers/colour_math.h"
#include "pipeline/readers/contained_paths.h"
#include "pipeline/readers/format_readers.h"
#include "pipeline/readers/mtl_reader.h"
#include "pipeline/readers/text_scan.h"

namespace cellbake {
namespace {

// One face corner after index resolution: a position index and optional
// texcoord and normal indices (-1 when absent).
struct ObjCorner {
  std::uint32_t vertex = 0;
  std::int64_t texcoord = -1;
  std::int64_t normal = -1;
};

class ObjReader {
 public:
  ObjReader(const std::filesystem::path& file, const TriangleCallback& emit, const ReadOptions& options)
      : file_(file), in_(file), emit_(emit), options_(options) {
    info_.format = "obj";
    info_.materials.push_back(default_material());
  }

  ModelInfo run() {
    std::string_view line;
    while (in_.next_line(line)) {
      TextScan scan(line);
      scan.skip_blanks();
      if (scan.p == scan.end) continue;
      const char c0 = scan.p[0];
      const char c1 = scan.p + 1 < scan.end ? scan.p[1] : ' ';
      if (c0 == 'v' && is_blank(c1)) {
        ++scan.p;
        parse_vertex(scan);
      } else if (c0 == 'f' && is_blank(c1)) {
        ++scan.p;
        parse_face(scan);
      } else if (c0 == 'v' && c1 == 't') {
        scan.p += 2;
        parse_texcoord(scan);
      } else if (c0 == 'v' && c1 == 'n') {
        scan.p += 2;
        parse_normal(scan);
      } else if (c0 == 'u' || c0 == 'm') {
        const std::string_view key = scan.token();
        if (key == "usemtl") use_material(std::string(scan.rest()));
        if (key == "mtllib") load_libraries(scan.rest());
      }
    }
    record_vertex_colour_use(info_, seen_colours_, ignored_colours_);
    // map_Kd paths are already resolved against their MTL's folder (read_mtl):
    // handed over as files, so ingest does not resolve them a second time
    // against the OBJ's folder (issue #41: "ingest sub/m.obj" looked in sub/sub/).
    for (std::uint32_t m = 1; m < info_.materials.size(); ++m)
      if (!info_.materials[m].texture.empty()) info_.textures[m].file = info_.materials[m].texture;
    return std::move(info_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(in_.name(), at_line(in_.line_number()), what);
  }

  void parse_vertex(TextScan& scan) {
    Vec3d p;
    if (!scan.number(p.x) || !scan.number(p.y) || !scan.number(p.z))
      fail("malformed vertex (expected 'v x y z')");
    if (!is_finite(p)) fail("non-finite coordinate");
    double extra[4];
    int extras = 0;
    while (extras < 4 && !scan.at_end()) {
      if (!scan.number(extra[extras])) fail("malformed number in vertex");
      ++extras;
    }
    if (!scan.at_end()) fail("too many values in vertex");
    if (extras >= 3) {
      if (vertex_colours_.empty()) {
        vertex_colours_.resize(positions_.size());
        has_colour_.resize(positions_.size(), 0);
      }
      const std::uint8_t alpha = extras == 4 ? unit_to_byte(extra[3]) : 255;
      vertex_colours_.push_back(
          {unit_to_byte(extra[0]), unit_to_byte(extra[1]), unit_to_byte(extra[2]), alpha});
      has_colour_.push_back(1);
      seen_colours_.add(vertex_colours_.back());
    } else if (!vertex_colours_.empty()) {
      vertex_colours_.emplace_back();
      has_colour_.push_back(0);
    }
    positions_.push_back(p);
  }

  void parse_texcoord(TextScan& scan) {
    double u = 0, v = 0;
    if (!scan.number(u)) fail("malformed texture coordinate");
    if (!scan.at_end() && !scan.number(v)) fail("malformed texture coordinate");
    texcoords_.push_back({static_cast<float>(u), static_cast<float>(v)});
  }

  void parse_normal(TextScan& scan) {
    double x = 0, y = 0, z = 0;
    if (!scan.number(x) || !scan.number(y) || !scan.number(z)) fail("malformed normal (expected 'vn x y z')");
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) fail("non-finite normal");
    normals_.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  }

  // Resolves a 1-based (or negative, relative) OBJ index against `count` items.
  std::uint64_t resolve(std::int64_t raw, std::uint64_t count, const char* what) const {
    if (raw == 0) fail(std::string(what) + " index 0 is invalid (OBJ indices start at 1)");
    if (raw > 0) {
      if (static_cast<std::uint64_t>(raw) > count)
        fail(std::string(what) + " index " + std::to_string(raw) + " out of range (" + std::to_string(count) +
             " defined so far)");
      return static_cast<std::uint64_t>(raw - 1);
    }
    if (static_cast<std::uint64_t>(-(raw + 1)) >= count)
      fail(std::string(what) + " index " + std::to_string(raw) + " out of range (" + std::to_string(count) +
           " defined so far)");
    return count - static_cast<std::uint64_t>(-raw);
  }

  ObjCorner parse_corner(TextScan& scan) {
    std::int64_t raw;
    if (!scan.integer_prefix(raw)) fail("malformed face corner");
    ObjCorner corner;
    corner.vertex = static_cast<std::uint32_t>(resolve(raw, positions_.size(), "vertex"));
    if (scan.p < scan.end && *scan.p == '/') {
      ++scan.p;
      if (scan.p < scan.end && *scan.p != '/') {
        if (!scan.integer_prefix(raw)) fail("malformed face corner");
        corner.texcoord = static_cast<std::int64_t>(resolve(raw, texcoords_.size(), "texture coordinate"));
      }
      if (scan.p < scan.end && *scan.p == '/') {
        ++scan.p;
        if (!scan.integer_prefix(raw)) fail("malformed face corner");
        corner.normal = static_cast<std::int64_t>(resolve(raw, normals_.size(), "normal"));
      }
    }
    if (scan.p < scan.end && !is_blank(*scan.p)) fail("malformed face corner");
    return corner;
  }

  void parse_face(TextScan& scan) {
    ObjCorner first, previous;
    int corners = 0;
    while (!scan.at_end()) {
      const ObjCorner corner = parse_corner(scan);
      if (corners >= 2) emit_triangle(first, previous, corner);
      if (corners == 0) first = corner;
      previous = corner;
      ++corners;
    }
    if (corners < 3) fail("face with fewer than 3 vertices");
    if (corners > 3) ++info_.polygons_triangulated;
  }

  // True when the file's vertex colours are not all equal: known once the
  // colours read so far differ, else settled by scan_vertex_colours().
  bool vertex_colours_vary() {
    if (seen_colours_.varies) return true;
    if (!file_colours_vary_) file_colours_vary_ = scan_vertex_colours();
    return *file_colours_vary_;
  }

  // A second pass over the file's "v" lines: true at the first vertex colour
  // that differs from the first one. Malformed lines are skipped (the main
  // pass reports them).
  bool scan_vertex_colours() {
    BufferedInput in(file_);
    ColourVariation variation;
    std::string_view line;
    while (in.next_line(line)) {
      TextScan scan(line);
      scan.skip_blanks();
      if (scan.end - scan.p < 2 || scan.p[0] != 'v' || !is_blank(scan.p[1])) continue;
      ++scan.p;
      double values[7];
      int count = 0;
      while (count < 7 && !scan.at_end() && scan.number(values[count])) ++count;
      if (count < 6 || !scan.at_end()) continue;
      variation.add({unit_to_byte(values[3]), unit_to_byte(values[4]), unit_to_byte(values[5]),
                     count == 7 ? unit_to_byte(values[6]) : std::uint8_t{255}});
      if (variation.varies) return true;
    }
    return false;
  }

  void emit_triangle(const ObjCorner& a, const ObjCorner& b, const ObjCorner& c) {
    Triangle t;
    t.material = material_;
    const Rgba8 material_colour = info_.materials[material_].color;
    const ObjCorner* corners[3] = {&a, &b, &c};
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t v = corners[i]->vertex;
      t.p[i] = positions_[v];
      const bool coloured = !has_colour_.empty() && has_colour_[v];
      const bool vary = !coloured || material_ == 0 || vertex_colours_vary();
      ignored_colours_ |= !vary;
      t.color[i] = corner_colour(material_colour, material_, coloured ? &vertex_colours_[v] : nullptr, vary);
      if (corners[i]->texcoord >= 0) t.uv[i] = texcoords_[static_cast<std::size_t>(corners[i]->texcoord)];
    }
    // Normals only when every corner names one; a face without them is flat.
    t.has_normals = a.normal >= 0 && b.normal >= 0 && c.normal >= 0;
    if (t.has_normals)
      for (int i = 0; i < 3; ++i) t.normal[i] = normals_[static_cast<std::size_t>(corners[i]->normal)];
    emit_(t);
    ++info_.triangles_emitted;
  }

  void use_material(const std::string& name) {
    const auto found = material_by_name_.find(name);
    material_ = found == material_by_name_.end() ? 0 : found->second;
  }

  // "mtllib a.mtl [b.mtl ...]": names are resolved against the OBJ's folder; a
  // single name containing blanks is tried first. Missing or unreadable
  // libraries, and (unless allowed) those outside the OBJ's folder, are
  // skipped with a warning (their materials stay default grey).
  void load_libraries(std::string_view operand) {
    if (operand.empty()) return;
    if (contained(std::string(operand)) &&
        read_mtl(file_.parent_path() / std::string(operand), info_.materials, material_by_name_))
      return;
    TextScan names(operand);
    for (std::string_view name = names.token(); !name.empty(); name = names.token()) {
      const std::string library(name);
      const std::string at = at_line(in_.line_number()) + ": mtllib '" + library + "': ";
      if (!contained(library))
        info_.warnings.push_back(at + kOutsideFolder + "; its materials are default grey");
      else if (!read_mtl(file_.parent_path() / library, info_.materials, material_by_name_))
        info_.warnings.push_back(at + "missing or unreadable; its materials are default grey");
    }
  }

  bool contained(const std::string& library) const {
    return options_.allow_outside_paths ||
           path_inside_folder(file_.parent_path(), file_.parent_path() / library);
  }

  std::filesystem::path file_;
  BufferedInput in_;
  const TriangleCallback& emit_;
  ReadOptions options_;
  ModelInfo info_;
  std::vector<Vec3d> positions_;
  std::vector<Rgba8> vertex_colours_;  // empty until the first coloured vertex
  std::vector<std::uint8_t> has_colour_;
  ColourVariation seen_colours_;           // every vertex colour read so far
  std::optional<bool> file_colours_vary_;  // settled by scan_vertex_colours()
  bool ignored_colours_ = false;           // some corner's uniform colour gave way to its material's
  std::vector<Uv> texcoords_;
  std::vector<Vec3f> normals_;
  std::unordered_map<std::string, std::uint32_t> material_by_name_;
  std::uint32_t material_ = 0;
};

}  // namespace

ModelInfo read_obj(const std::filesystem::path& file, const TriangleCallback& emit,
                   const ReadOptions& options) {
  return ObjReader(file, emit, options).run();
}

}  // namespace cellbake
