// Vertex and index streams of exported glTF meshes, quantised as the
// KHR_mesh_quantization extension allows (Khronos, 2020; the layout of
// gltfpack, Kapoulkine, meshoptimizer): positions as int16 normalised around
// a centre with one uniform scale per mesh (the dequantisation is the node's
// translation and scale, so normals need no correction), normals as int8
// normalised, texture coordinates as uint16 normalised (float where they
// leave [0, 1]; integers on a grid the material's KHR_texture_transform
// scales back where the mesh says so), colours as uint16 normalised linear RGBA (glTF vertex
// colours are linear, cellbake's are the sRGB values shown; 16 bits keep the
// darks that 8 linear bits would band); every vertex stream 4-byte aligned. With compression, each stream is coded with meshoptimizer's vertex
// and index codecs (EXT_meshopt_compression).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/export/glb_builder.h"
#include "stages/geometry.h"

namespace cellbake {

// One glTF primitive's triangles before quantisation. Attribute vectors are
// empty or one per position.
struct ExportMesh {
  std::vector<Vec3d> positions;  // relative to the mesh node's parent origin
  std::vector<Vec3f> normals;    // unit length
  std::vector<Rgba8> colors;     // as shown (sRGB-encoded)
  std::vector<Uv> uvs;           // glTF convention: (0, 0) at the image's top-left corner
  std::vector<std::uint32_t> indices;  // three per triangle
  // > 0: uvs are written as unsigned integers round(u * uv_grid_width),
  // round(v * uv_grid_height), which the material's KHR_texture_transform scales back.
  int uv_grid_width = 0, uv_grid_height = 0;
  std::size_t triangle_count() const { return indices.size() / 3; }
};

// The dequantisation of a mesh's positions: world = translation + scale * q / 32767
// for int16 values q (the node's translation and uniform scale). With `bits`
// bits, q lie in [-(2^(bits-1) - 1), 2^(bits-1) - 1]: the same int16 streams,
// whose high bytes vary less, which the meshoptimizer codec's byte deltas
// then code in fewer bits (the demo's chunks: 35 % smaller at 12 bits than at 16).
struct PositionQuantization {
  Vec3d translation;
  double scale = 1;
  int bits = 16;
};

// The quantisation of positions within `bounds` (not empty) to `bits`
// (8..16) bits: the box centre, and a scale that maps the largest half extent
// (at least 1e-9, so a flat or point-like mesh still has one) onto
// 2^(bits-1) - 1. Throws std::invalid_argument for an empty or non-finite box
// or bits outside 8..16.
PositionQuantization position_quantization(const Box3d& bounds, int bits = 16);

// The fewest bits (8..16) whose position_error_bound over `bounds` (not
// empty, finite) is at most `tolerance`; 16 when none is, or for a tolerance <= 0.
int position_bits_within(const Box3d& bounds, double tolerance);

// The largest distance per axis between a position in the quantised bounds
// and its dequantised value: half a step, (largest half extent) / (2^(bits-1) - 1) / 2,
// plus float32 rounding of the dequantised value.
double position_error_bound(const PositionQuantization& q);

// Positions as int16 x, y, z and a zero pad (8-byte stride). Throws
// std::invalid_argument for a position outside the quantisation's range.
std::vector<std::int16_t> quantize_positions(std::span<const Vec3d> positions, const PositionQuantization& q);
// Unit normals as int8 x, y, z and a zero pad (4-byte stride), rounded to the nearest 1/127.
std::vector<std::int8_t> quantize_normals(std::span<const Vec3f> normals);
// Texture coordinates in [0, 1] as uint16 u, v (rounded to the nearest 1/65535).
std::vector<std::uint16_t> quantize_uvs(std::span<const Uv> uvs);
bool uvs_in_unit_square(std::span<const Uv> uvs);
// sRGB-encoded colours as linear uint16 r, g, b, a (alpha linear already),
// the sRGB transfer function (IEC 61966-2-1) inverted, rounded to the nearest 1/65535.
std::vector<std::uint16_t> linear_colors(std::span<const Rgba8> colors);
// The same at 8 bits (rounded to the nearest 1/255 of linear).
std::vector<std::uint8_t> linear_colors8(std::span<const Rgba8> colors);

// Merges vertices whose position and attributes are all equal, keeping the
// first of each in order, and renumbers the indices. Returns the vertices removed.
std::size_t weld_vertices(ExportMesh& mesh);

// Reorders `mesh`'s triangles for the vertex cache and its vertices for
// fetch (meshoptimizer), which the vertex and index codecs then code smaller.
// Same triangles, same winding.
void optimize_mesh_order(ExportMesh& mesh);

// The vertex streams of every primitive of a file, pooled by kind (attribute
// and stride) into one buffer view each, every accessor at its offset
// (gltfpack's layout): a view's JSON per kind, not per stream (the demo's tdm
// cell: JSON 145 -> 85 kB). Indices keep a view per primitive. A view is
// reserved when its kind first appears and written by flush().
class StreamPool {
 public:
  // Streams go into `glb` (which must outlive this), meshoptimizer-coded when `compress`.
  StreamPool(GlbBuilder& glb, bool compress) : glb_(glb), compress_(compress) {}
  struct Place {
    int view = -1;
    std::size_t byte_offset = 0;
  };
  // Appends `count` vertices of `stride` bytes of attribute `kind` ("POSITION" ...).
  Place add_vertices(const std::string& kind, std::span<const std::uint8_t> bytes, std::size_t count, int stride);
  // A view of a primitive's indices (a multiple of 3), `index_size` (2 or 4) bytes each.
  Place add_indices(std::span<const std::uint32_t> indices, int index_size);
  // Writes every pooled view into the builder; once, before GlbBuilder::finish().
  void flush();
  GlbBuilder& glb() { return glb_; }
  bool compress() const { return compress_; }

 private:
  struct Pool {
    std::string kind;
    int stride = 0;  // bytes per element (the index size for indices)
    bool indices = false;
    int view = -1;
    std::vector<std::uint8_t> bytes;
    std::size_t count = 0;
  };
  Pool& pool(const std::string& kind, int stride, bool indices);
  GlbBuilder& glb_;
  bool compress_;
  std::vector<Pool> pools_;
};

// Appends the primitive's streams to `pool` (quantised with `q`; compressed
// with meshoptimizer's codecs when the pool compresses) and returns its glTF
// primitive object: attributes (POSITION with min/max, NORMAL, COLOR_0 as
// uint16 or, with `color_bits` 8, uint8 linear RGBA, TEXCOORD_0 as present:
// on the mesh's uv grid as uint16 integers round(u * uv_grid_width), not normalised), indices (uint16 when there are fewer than 65535
// vertices, else uint32) and mode 4 (triangles). Marks KHR_mesh_quantization
// required. Throws std::invalid_argument for attribute vectors not one per
// position, an index out of range or an index count not a multiple of 3.
nlohmann::json add_primitive_streams(StreamPool& pool, const ExportMesh& mesh, const PositionQuantization& q,
                                     int color_bits = 16);

}  // namespace cellbake
