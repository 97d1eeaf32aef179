// Stage `encode`, face meshes: quantised positions and texture coordinates
// through meshoptimizer's vertex and index codecs (A. Kapoulkine,
// meshoptimizer 0.18, "vertex/index buffer compression"). The decoder treats
// its input as untrusted and validates every field before allocating.
#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "stages/encode/encode.h"
#include "stages/encode/encode_grid_mesh.h"
#include "stages/little_endian.h"

namespace cellbake {
namespace {

using little_endian::put_u32;
using little_endian::get_u32;
using little_endian::put_f32;
using little_endian::get_f32;


constexpr std::array<std::uint8_t, 4> kMagic = {'C', 'B', 'F', 'M'};
constexpr std::uint8_t kVersion = 1;
constexpr std::uint8_t kUvBits = 16;
constexpr std::uint8_t kFlagHasUvs = 1;
constexpr std::size_t kHeaderSize = 64;

// One quantised vertex as fed to the meshoptimizer vertex codec (12 bytes: the
// codec needs a multiple of 4).
struct QuantizedVertex {
  std::uint16_t x, y, z, u, v, pad;
};
static_assert(sizeof(QuantizedVertex) == 12);

struct Header {
  std::uint8_t position_bits = 16;
  std::uint8_t flags = 0;
  std::uint32_t vertex_count = 0;
  std::uint32_t index_count = 0;
  std::array<float, 3> pos_lo{}, pos_hi{};
  std::array<float, 2> uv_lo{}, uv_hi{};
  std::uint32_t vertex_bytes = 0;
  std::uint32_t index_bytes = 0;
};


// Layout: magic[4] version bits uv_bits flags | vertex_count index_count |
// pos_lo[3] pos_hi[3] uv_lo[2] uv_hi[2] (f32) | vertex_bytes index_bytes.
void write_header(std::uint8_t* out, const Header& h) {
  std::memcpy(out, kMagic.data(), 4);
  out[4] = kVersion;
  out[5] = h.position_bits;
  out[6] = kUvBits;
  out[7] = h.flags;
  put_u32(out + 8, h.vertex_count);
  put_u32(out + 12, h.index_count);
  for (int i = 0; i < 3; ++i) put_f32(out + 16 + 4 * i, h.pos_lo[i]);
  for (int i = 0; i < 3; ++i) put_f32(out + 28 + 4 * i, h.pos_hi[i]);
  for (int i = 0; i < 2; ++i) put_f32(out + 40 + 4 * i, h.uv_lo[i]);
  for (int i = 0; i < 2; ++i) put_f32(out + 48 + 4 * i, h.uv_hi[i]);
  put_u32(out + 56, h.vertex_bytes);
  put_u32(out + 60, h.index_bytes);
}

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("face mesh blob: " + what); }

Header read_header(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size < kHeaderSize)
    fail(std::to_string(size) + " bytes, shorter than the " + std::to_string(kHeaderSize) + "-byte header");
  if (std::memcmp(data, kMagic.data(), 4) != 0) fail("bad magic");
  if (data[4] != kVersion) fail("unsupported version " + std::to_string(data[4]));
  Header h;
  h.position_bits = data[5];
  if (h.position_bits < 1 || h.position_bits > 16)
    fail("position bits " + std::to_string(h.position_bits) + " outside 1..16");
  if (data[6] != kUvBits) fail("uv bits " + std::to_string(data[6]) + " (expected 16)");
  h.flags = data[7];
  if ((h.flags & ~kFlagHasUvs) != 0) fail("unknown flags " + std::to_string(h.flags));
  h.vertex_count = get_u32(data + 8);
  h.index_count = get_u32(data + 12);
  for (int i = 0; i < 3; ++i) h.pos_lo[i] = get_f32(data + 16 + 4 * i);
  for (int i = 0; i < 3; ++i) h.pos_hi[i] = get_f32(data + 28 + 4 * i);
  for (int i = 0; i < 2; ++i) h.uv_lo[i] = get_f32(data + 40 + 4 * i);
  for (int i = 0; i < 2; ++i) h.uv_hi[i] = get_f32(data + 48 + 4 * i);
  h.vertex_bytes = get_u32(data + 56);
  h.index_bytes = get_u32(data + 60);

  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(h.pos_lo[i]) || !std::isfinite(h.pos_hi[i]) || !(h.pos_lo[i] <= h.pos_hi[i]))
      fail("bad position bounds");
  for (int i = 0; i < 2; ++i)
    if (!std::isfinite(h.uv_lo[i]) || !std::isfinite(h.uv_hi[i]) || !(h.uv_lo[i] <= h.uv_hi[i]))
      fail("bad uv bounds");
  if (std::uint64_t{kHeaderSize} + h.vertex_bytes + h.index_bytes != size)
    fail("stream sizes " + std::to_string(h.vertex_bytes) + " + " + std::to_string(h.index_bytes) +
         " do not match the blob size " + std::to_string(size));
  if (h.index_count % 3 != 0)
    fail("index count " + std::to_string(h.index_count) + " is not a multiple of 3");
  if (h.vertex_count == 0 && (h.index_count != 0 || h.vertex_bytes != 0))
    fail("indices or vertex data without vertices");
  if (h.index_count == 0 && h.index_bytes != 0) fail("index data without indices");
  // The codecs cannot represent more than this per byte (vertex codec: >= 2
  // header bits per 16 vertices per byte column; index codec: a code byte per
  // triangle plus a 17-byte frame), so a larger count is a lie that would
  // otherwise make us allocate on the blob's word.
  if (std::uint64_t{h.vertex_count} > 8 * std::uint64_t{h.vertex_bytes})
    fail("vertex count too large for its stream");
  if (h.index_count > 0 && std::uint64_t{h.index_count} / 3 + 17 > h.index_bytes)
    fail("index count too large for its stream");
  return h;
}

std::uint16_t quantize(double value, double lo, double hi, std::uint32_t max_q) {
  if (!(hi > lo)) return 0;
  const double q = std::nearbyint((value - lo) / (hi - lo) * max_q);
  return static_cast<std::uint16_t>(std::clamp(q, 0.0, static_cast<double>(max_q)));
}

float dequantize(std::uint16_t q, float lo, float hi, std::uint32_t max_q) {
  return static_cast<float>(double{lo} + q * ((double{hi} - double{lo}) / max_q));
}

void check_mesh(const FaceMesh& mesh, int bits) {
  const std::string where = "encode_face_mesh: ";
  if (bits < 1 || bits > 16)
    throw std::invalid_argument(where + "position_bits " + std::to_string(bits) + " outside 1..16");
  if (mesh.indices.size() % 3 != 0)
    throw std::invalid_argument(where + "index count " + std::to_string(mesh.indices.size()) +
                                " is not a multiple of 3");
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
    throw std::invalid_argument(where + std::to_string(mesh.uvs.size()) + " uvs for " +
                                std::to_string(mesh.positions.size()) + " positions");
  if (mesh.positions.size() > std::numeric_limits<std::uint32_t>::max() / 2 ||
      mesh.indices.size() > std::numeric_limits<std::uint32_t>::max() / 2)
    throw std::invalid_argument(where + "mesh too large");
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3f& p = mesh.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::invalid_argument(where + "position " + std::to_string(i) + " is not finite");
  }
  for (std::size_t i = 0; i < mesh.uvs.size(); ++i)
    if (!std::isfinite(mesh.uvs[i].u) || !std::isfinite(mesh.uvs[i].v))
      throw std::invalid_argument(where + "uv " + std::to_string(i) + " is not finite");
  for (std::size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= mesh.positions.size())
      throw std::invalid_argument(where + "index " + std::to_string(i) + " = " +
                                  std::to_string(mesh.indices[i]) + " is past the " +
                                  std::to_string(mesh.positions.size()) + " vertices");
}

// The mesh with triangles in vertex-cache order and vertices in first-use
// order (unreferenced vertices dropped).
FaceMesh optimized_order(const FaceMesh& mesh) {
  FaceMesh out;
  const std::size_t n = mesh.positions.size();
  std::vector<std::uint32_t> indices(mesh.indices.size());
  meshopt_optimizeVertexCache(indices.data(), mesh.indices.data(), mesh.indices.size(), n);
  std::vector<std::uint32_t> remap(n);
  const std::size_t used = meshopt_optimizeVertexFetchRemap(remap.data(), indices.data(), indices.size(), n);
  out.indices.resize(indices.size());
  meshopt_remapIndexBuffer(out.indices.data(), indices.data(), indices.size(), remap.data());
  out.positions.resize(used);
  if (!mesh.uvs.empty()) out.uvs.resize(used);
  for (std::size_t v = 0; v < n; ++v) {
    if (remap[v] == ~0u) continue;
    out.positions[remap[v]] = mesh.positions[v];
    if (!mesh.uvs.empty()) out.uvs[remap[v]] = mesh.uvs[v];
  }
  return out;
}

}  // namespace

std::vector<std::uint8_t> encode_face_mesh(const FaceMesh& input, const MeshEncodeParams& params) {
  check_mesh(input, params.position_bits);
  if (params.face >= 0 && params.face_size > 0)
    if (auto grid = encode_grid_face_mesh(input, params.face, params.face_size, params.depth_error_relative,
                                          params.zstd_level))
      return std::move(*grid);
  const FaceMesh mesh = params.optimize_order ? optimized_order(input) : input;

  Header h;
  h.position_bits = static_cast<std::uint8_t>(params.position_bits);
  h.flags = mesh.uvs.empty() ? 0 : kFlagHasUvs;
  h.vertex_count = static_cast<std::uint32_t>(mesh.positions.size());
  h.index_count = static_cast<std::uint32_t>(mesh.indices.size());
  if (!mesh.positions.empty()) {
    h.pos_lo = {mesh.positions[0].x, mesh.positions[0].y, mesh.positions[0].z};
    h.pos_hi = h.pos_lo;
    for (const Vec3f& p : mesh.positions) {
      const std::array<float, 3> c = {p.x, p.y, p.z};
      for (int i = 0; i < 3; ++i)
        h.pos_lo[i] = std::min(h.pos_lo[i], c[i]), h.pos_hi[i] = std::max(h.pos_hi[i], c[i]);
    }
  }
  if (!mesh.uvs.empty()) {
    h.uv_lo = {mesh.uvs[0].u, mesh.uvs[0].v};
    h.uv_hi = h.uv_lo;
    for (const Uv& t : mesh.uvs) {
      h.uv_lo = {std::min(h.uv_lo[0], t.u), std::min(h.uv_lo[1], t.v)};
      h.uv_hi = {std::max(h.uv_hi[0], t.u), std::max(h.uv_hi[1], t.v)};
    }
  }

  const std::uint32_t max_pos = (1u << params.position_bits) - 1, max_uv = (1u << kUvBits) - 1;
  std::vector<QuantizedVertex> vertices(mesh.positions.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Vec3f& p = mesh.positions[i];
    QuantizedVertex& q = vertices[i];
    q.x = quantize(p.x, h.pos_lo[0], h.pos_hi[0], max_pos);
    q.y = quantize(p.y, h.pos_lo[1], h.pos_hi[1], max_pos);
    q.z = quantize(p.z, h.pos_lo[2], h.pos_hi[2], max_pos);
    q.u = mesh.uvs.empty() ? 0 : quantize(mesh.uvs[i].u, h.uv_lo[0], h.uv_hi[0], max_uv);
    q.v = mesh.uvs.empty() ? 0 : quantize(mesh.uvs[i].v, h.uv_lo[1], h.uv_hi[1], max_uv);
    q.pad = 0;
  }

  std::vector<std::uint8_t> vertex_stream, index_stream;
  if (!vertices.empty()) {
    vertex_stream.resize(meshopt_encodeVertexBufferBound(vertices.size(), sizeof(QuantizedVertex)));
    vertex_stream.resize(meshopt_encodeVertexBuffer(vertex_stream.data(), vertex_stream.size(),
                                                    vertices.data(), vertices.size(),
                                                    sizeof(QuantizedVertex)));
    if (vertex_stream.empty()) throw std::runtime_error("encode_face_mesh: vertex codec failed");
  }
  if (!mesh.indices.empty()) {
    index_stream.resize(meshopt_encodeIndexBufferBound(mesh.indices.size(), mesh.positions.size()));
    index_stream.resize(meshopt_encodeIndexBuffer(index_stream.data(), index_stream.size(),
                                                  mesh.indices.data(), mesh.indices.size()));
    if (index_stream.empty()) throw std::runtime_error("encode_face_mesh: index codec failed");
  }
  h.vertex_bytes = static_cast<std::uint32_t>(vertex_stream.size());
  h.index_bytes = static_cast<std::uint32_t>(index_stream.size());

  std::vector<std::uint8_t> blob(kHeaderSize + vertex_stream.size() + index_stream.size());
  write_header(blob.data(), h);
  std::copy(vertex_stream.begin(), vertex_stream.end(), blob.begin() + kHeaderSize);
  std::copy(index_stream.begin(), index_stream.end(),
            blob.begin() + static_cast<std::ptrdiff_t>(kHeaderSize + vertex_stream.size()));
  return blob;
}

FaceMesh decode_face_mesh(const std::uint8_t* data, std::size_t size) {
  if (data != nullptr && size > 4 && data[4] == kGridMeshVersion && std::memcmp(data, kMagic.data(), 4) == 0)
    return decode_grid_face_mesh(data, size);
  const Header h = read_header(data, size);
  FaceMesh mesh;
  if (h.vertex_count == 0) return mesh;

  std::vector<QuantizedVertex> vertices(h.vertex_count);
  if (meshopt_decodeVertexBuffer(vertices.data(), vertices.size(), sizeof(QuantizedVertex),
                                 data + kHeaderSize, h.vertex_bytes) != 0)
    fail("vertex stream does not decode");
  const std::uint32_t max_pos = (1u << h.position_bits) - 1, max_uv = (1u << kUvBits) - 1;
  const bool has_uvs = (h.flags & kFlagHasUvs) != 0;
  mesh.positions.resize(vertices.size());
  if (has_uvs) mesh.uvs.resize(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const QuantizedVertex& q = vertices[i];
    if (q.x > max_pos || q.y > max_pos || q.z > max_pos)
      fail("vertex " + std::to_string(i) + " exceeds the position bits");
    if (q.pad != 0 || (!has_uvs && (q.u != 0 || q.v != 0)))
      fail("vertex " + std::to_string(i) + " has stray bits");
    mesh.positions[i] = {dequantize(q.x, h.pos_lo[0], h.pos_hi[0], max_pos),
                         dequantize(q.y, h.pos_lo[1], h.pos_hi[1], max_pos),
                         dequantize(q.z, h.pos_lo[2], h.pos_hi[2], max_pos)};
    if (has_uvs)
      mesh.uvs[i] = {dequantize(q.u, h.uv_lo[0], h.uv_hi[0], max_uv),
                     dequantize(q.v, h.uv_lo[1], h.uv_hi[1], max_uv)};
  }

  mesh.indices.resize(h.index_count);
  if (h.index_count > 0 &&
      meshopt_decodeIndexBuffer(mesh.indices.data(), mesh.indices.size(), sizeof(std::uint32_t),
                                data + kHeaderSize + h.vertex_bytes, h.index_bytes) != 0)
    fail("index stream does not decode");
  for (std::size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= h.vertex_count)
      fail("index " + std::to_string(i) + " = " + std::to_string(mesh.indices[i]) + " is past the " +
           std::to_string(h.vertex_count) + " vertices");
  return mesh;
}

double face_mesh_position_error_bound(const FaceMesh& mesh, int position_bits) {
  if (mesh.positions.empty()) return 0;
  double extent = 0, magnitude = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3f& p : mesh.positions) {
      const double v = axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
    extent = std::max(extent, hi - lo);
    magnitude = std::max({magnitude, std::fabs(lo), std::fabs(hi)});
  }
  const double step = extent / ((1u << position_bits) - 1);
  return 0.5 * step + magnitude * std::numeric_limits<float>::epsilon();
}

double face_mesh_uv_error_bound(const FaceMesh& mesh) {
  if (mesh.uvs.empty()) return 0;
  double extent = 0, magnitude = 0;
  for (int axis = 0; axis < 2; ++axis) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Uv& t : mesh.uvs) {
      const double v = axis == 0 ? t.u : t.v;
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
    extent = std::max(extent, hi - lo);
    magnitude = std::max({magnitude, std::fabs(lo), std::fabs(hi)});
  }
  return 0.5 * extent / 65535.0 + magnitude * std::numeric_limits<float>::epsilon();
}

}  // namespace cellbake
