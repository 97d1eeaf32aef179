#include "pipeline/export/gltf_vertex_streams.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

constexpr double kInt16Max = 32767.0;

template <class T>
std::span<const std::uint8_t> as_bytes_of(const std::vector<T>& v) {
  return {reinterpret_cast<const std::uint8_t*>(v.data()), v.size() * sizeof(T)};
}

void check_mesh(const ExportMesh& m) {
  const std::size_t n = m.positions.size();
  const auto check = [n](std::size_t size, const char* what) {
    if (size != 0 && size != n)
      throw std::invalid_argument(std::string("glTF export: ") + std::to_string(size) + " " + what + " for " +
                                  std::to_string(n) + " positions");
  };
  check(m.normals.size(), "normals");
  check(m.colors.size(), "colours");
  check(m.uvs.size(), "texture coordinates");
  if (m.indices.size() % 3 != 0)
    throw std::invalid_argument("glTF export: " + std::to_string(m.indices.size()) + " indices, not whole triangles");
  for (std::uint32_t i : m.indices)
    if (i >= n) throw std::invalid_argument("glTF export: index " + std::to_string(i) + " out of range");
}

// Reorders every attribute by `remap` (old vertex -> new vertex) into `count` vertices.
template <class T>
void remap_stream(std::vector<T>& stream, const std::vector<unsigned>& remap, std::size_t count) {
  if (stream.empty()) return;
  std::vector<T> out(count);
  meshopt_remapVertexBuffer(out.data(), stream.data(), stream.size(), sizeof(T), remap.data());
  stream = std::move(out);
}

void remap_mesh(ExportMesh& m, const std::vector<unsigned>& remap, std::size_t count) {
  remap_stream(m.positions, remap, count);
  remap_stream(m.normals, remap, count);
  remap_stream(m.colors, remap, count);
  remap_stream(m.uvs, remap, count);
  meshopt_remapIndexBuffer(m.indices.data(), m.indices.data(), m.indices.size(), remap.data());
}

}  // namespace

namespace {
int position_levels(int bits) { return (1 << (bits - 1)) - 1; }
}  // namespace

PositionQuantization position_quantization(const Box3d& bounds, int bits) {
  if (bounds.empty() || !is_finite(bounds.lo) || !is_finite(bounds.hi))
    throw std::invalid_argument("glTF export: positions need finite, non-empty bounds");
  if (bits < 8 || bits > 16) throw std::invalid_argument("glTF export: position bits " + std::to_string(bits) + " outside 8..16");
  const Vec3d half = bounds.extent() * 0.5;
  const double largest = std::max({half.x, half.y, half.z, 1e-9});
  // q = round(offset / largest * levels), so that q = +-levels at the extremes.
  return {bounds.center(), largest * kInt16Max / double(position_levels(bits)), bits};
}

int position_bits_within(const Box3d& bounds, double tolerance) {
  if (!(tolerance > 0)) return 16;
  int bits = 8;
  while (bits < 16 && position_error_bound(position_quantization(bounds, bits)) > tolerance) ++bits;
  return bits;
}

double position_error_bound(const PositionQuantization& q) {
  const double largest = std::max({std::abs(q.translation.x), std::abs(q.translation.y), std::abs(q.translation.z)}) + q.scale;
  return q.scale / kInt16Max / 2 + 2 * largest * std::numeric_limits<float>::epsilon();
}

std::vector<std::int16_t> quantize_positions(std::span<const Vec3d> positions, const PositionQuantization& q) {
  std::vector<std::int16_t> out(positions.size() * 4, 0);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3d r = (positions[i] - q.translation) * (kInt16Max / q.scale);
    for (int a = 0; a < 3; ++a) {
      const double v = std::round(r[a]);
      if (!(std::abs(v) <= kInt16Max))
        throw std::invalid_argument("glTF export: position " + std::to_string(i) + " lies outside its quantisation range");
      out[4 * i + a] = static_cast<std::int16_t>(v);
    }
  }
  return out;
}

std::vector<std::int8_t> quantize_normals(std::span<const Vec3f> normals) {
  std::vector<std::int8_t> out(normals.size() * 4, 0);
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const float c[3] = {normals[i].x, normals[i].y, normals[i].z};
    for (int a = 0; a < 3; ++a)
      out[4 * i + a] = static_cast<std::int8_t>(std::lround(std::clamp(std::isfinite(c[a]) ? c[a] : 0.0f, -1.0f, 1.0f) * 127));
  }
  return out;
}

bool uvs_in_unit_square(std::span<const Uv> uvs) {
  return std::all_of(uvs.begin(), uvs.end(), [](const Uv& t) { return t.u >= 0 && t.u <= 1 && t.v >= 0 && t.v <= 1; });
}

std::vector<std::uint16_t> quantize_uvs(std::span<const Uv> uvs) {
  std::vector<std::uint16_t> out(uvs.size() * 2);
  for (std::size_t i = 0; i < uvs.size(); ++i) {
    out[2 * i] = static_cast<std::uint16_t>(std::lround(std::clamp(uvs[i].u, 0.0f, 1.0f) * 65535));
    out[2 * i + 1] = static_cast<std::uint16_t>(std::lround(std::clamp(uvs[i].v, 0.0f, 1.0f) * 65535));
  }
  return out;
}

std::vector<std::uint16_t> linear_colors(std::span<const Rgba8> colors) {
  std::array<std::uint16_t, 256> table;
  for (int c = 0; c < 256; ++c) {
    const double s = c / 255.0;
    const double linear = s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
    table[std::size_t(c)] = static_cast<std::uint16_t>(std::lround(linear * 65535));
  }
  std::vector<std::uint16_t> out(colors.size() * 4);
  for (std::size_t i = 0; i < colors.size(); ++i) {
    out[4 * i] = table[colors[i].r];
    out[4 * i + 1] = table[colors[i].g];
    out[4 * i + 2] = table[colors[i].b];
    out[4 * i + 3] = static_cast<std::uint16_t>(colors[i].a * 257);
  }
  return out;
}

std::vector<std::uint8_t> linear_colors8(std::span<const Rgba8> colors) {
  const std::vector<std::uint16_t> wide = linear_colors(colors);
  std::vector<std::uint8_t> out(wide.size());
  for (std::size_t i = 0; i < wide.size(); ++i) out[i] = static_cast<std::uint8_t>((wide[i] * 255 + 32767) / 65535);
  return out;
}

std::size_t weld_vertices(ExportMesh& m) {
  check_mesh(m);
  const std::size_t n = m.positions.size();
  if (n == 0) return 0;
  std::vector<meshopt_Stream> streams{{m.positions.data(), sizeof(Vec3d), sizeof(Vec3d)}};
  if (!m.normals.empty()) streams.push_back({m.normals.data(), sizeof(Vec3f), sizeof(Vec3f)});
  if (!m.colors.empty()) streams.push_back({m.colors.data(), sizeof(Rgba8), sizeof(Rgba8)});
  if (!m.uvs.empty()) streams.push_back({m.uvs.data(), sizeof(Uv), sizeof(Uv)});
  std::vector<unsigned> remap(n);
  const std::size_t kept =
      meshopt_generateVertexRemapMulti(remap.data(), m.indices.data(), m.indices.size(), n, streams.data(), streams.size());
  remap_mesh(m, remap, kept);
  return n - kept;
}

void optimize_mesh_order(ExportMesh& m) {
  check_mesh(m);
  const std::size_t n = m.positions.size();
  if (m.indices.empty()) return;
  meshopt_optimizeVertexCache(m.indices.data(), m.indices.data(), m.indices.size(), n);
  std::vector<unsigned> remap(n);
  const std::size_t used = meshopt_optimizeVertexFetchRemap(remap.data(), m.indices.data(), m.indices.size(), n);
  remap_mesh(m, remap, used);
}

StreamPool::Pool& StreamPool::pool(const std::string& kind, int stride, bool indices) {
  for (Pool& p : pools_)
    if (p.kind == kind && p.stride == stride && p.indices == indices) return p;
  Pool p;
  p.kind = kind;
  p.stride = stride;
  p.indices = indices;
  p.view = glb_.reserve_buffer_view();
  pools_.push_back(std::move(p));
  return pools_.back();
}

StreamPool::Place StreamPool::add_vertices(const std::string& kind, std::span<const std::uint8_t> bytes,
                                           std::size_t count, int stride) {
  Pool& p = pool(kind, stride, false);
  const Place place{p.view, p.bytes.size()};
  p.bytes.insert(p.bytes.end(), bytes.begin(), bytes.end());
  p.count += count;
  return place;
}

StreamPool::Place StreamPool::add_indices(std::span<const std::uint32_t> indices, int index_size) {
  // A view of its own: the index codec predicts each new vertex as the next
  // number, which a second primitive's indices (from 0 again) would defeat
  // (the demo's tdm cell: 2.3 times the bytes in one view).
  pools_.push_back({"indices", index_size, true, glb_.reserve_buffer_view(), {}, 0});
  Pool& p = pools_.back();
  const Place place{p.view, 0};
  for (std::uint32_t i : indices)
    for (int b = 0; b < index_size; ++b) p.bytes.push_back(static_cast<std::uint8_t>(i >> (8 * b)));
  p.count += indices.size();
  return place;
}

void StreamPool::flush() {
  for (const Pool& p : pools_) {
    const std::optional<int> stride = p.indices ? std::nullopt : std::optional<int>(p.stride);
    const int target = p.indices ? gltf::kElementArrayBuffer : gltf::kArrayBuffer;
    if (!compress_) {
      glb_.fill_buffer_view(p.view, p.bytes, stride, target);
    } else if (!p.indices) {
      std::vector<std::uint8_t> coded(meshopt_encodeVertexBufferBound(p.count, std::size_t(p.stride)));
      coded.resize(meshopt_encodeVertexBuffer(coded.data(), coded.size(), p.bytes.data(), p.count, std::size_t(p.stride)));
      glb_.fill_compressed_buffer_view(p.view, coded, p.count, p.stride, MeshoptMode::attributes, target);
    } else {
      std::vector<std::uint32_t> wide(p.count, 0);
      for (std::size_t i = 0; i < p.count; ++i)
        for (int b = 0; b < p.stride; ++b) wide[i] |= std::uint32_t(p.bytes[i * std::size_t(p.stride) + std::size_t(b)]) << (8 * b);
      std::vector<std::uint8_t> coded(meshopt_encodeIndexBufferBound(p.count, p.count));
      coded.resize(meshopt_encodeIndexBuffer(coded.data(), coded.size(), wide.data(), p.count));
      glb_.fill_compressed_buffer_view(p.view, coded, p.count, p.stride, MeshoptMode::triangles, target);
    }
  }
  pools_.clear();
}

nlohmann::json add_primitive_streams(StreamPool& pool, const ExportMesh& m, const PositionQuantization& q,
                                     int color_bits) {
  check_mesh(m);
  GlbBuilder& glb = pool.glb();
  glb.use_extension("KHR_mesh_quantization", true);
  const std::size_t n = m.positions.size();
  nlohmann::json attributes;
  const auto accessor = [&](const std::string& kind, std::span<const std::uint8_t> bytes, int stride,
                            int component_type, bool normalized, const std::string& type,
                            const std::vector<double>& lo = {}, const std::vector<double>& hi = {}) {
    const StreamPool::Place at = pool.add_vertices(kind, bytes, n, stride);
    return glb.add_accessor(at.view, component_type, normalized, n, type, lo, hi, at.byte_offset);
  };

  const std::vector<std::int16_t> positions = quantize_positions(m.positions, q);
  std::vector<double> lo(3, kInt16Max), hi(3, -kInt16Max);
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], double(positions[4 * i + a]));
      hi[a] = std::max(hi[a], double(positions[4 * i + a]));
    }
  if (n == 0) lo.assign(3, 0), hi.assign(3, 0);
  attributes["POSITION"] = accessor("POSITION", as_bytes_of(positions), 8, gltf::kShort, true, "VEC3", lo, hi);
  if (!m.normals.empty())
    attributes["NORMAL"] = accessor("NORMAL", as_bytes_of(quantize_normals(m.normals)), 4, gltf::kByte, true, "VEC3");
  if (!m.colors.empty())
    attributes["COLOR_0"] =
        color_bits == 8
            ? accessor("COLOR_0", as_bytes_of(linear_colors8(m.colors)), 4, gltf::kUnsignedByte, true, "VEC4")
            : accessor("COLOR_0", as_bytes_of(linear_colors(m.colors)), 8, gltf::kUnsignedShort, true, "VEC4");
  if (!m.uvs.empty()) {
    if (m.uv_grid_width > 0 && m.uv_grid_height > 0) {
      std::vector<std::uint16_t> grid(n * 2);
      for (std::size_t i = 0; i < n; ++i) {
        grid[2 * i] = static_cast<std::uint16_t>(std::lround(std::clamp(m.uvs[i].u, 0.0f, 1.0f) * m.uv_grid_width));
        grid[2 * i + 1] = static_cast<std::uint16_t>(std::lround(std::clamp(m.uvs[i].v, 0.0f, 1.0f) * m.uv_grid_height));
      }
      attributes["TEXCOORD_0"] = accessor("TEXCOORD_0 grid", as_bytes_of(grid), 4, gltf::kUnsignedShort, false, "VEC2");
    } else if (uvs_in_unit_square(m.uvs)) {
      attributes["TEXCOORD_0"] = accessor("TEXCOORD_0", as_bytes_of(quantize_uvs(m.uvs)), 4, gltf::kUnsignedShort, true, "VEC2");
    } else {
      attributes["TEXCOORD_0"] = accessor("TEXCOORD_0 float", as_bytes_of(m.uvs), 8, gltf::kFloat, false, "VEC2");
    }
  }

  // glTF forbids the index type's largest value (primitive restart).
  const bool short_indices = n < 65535;
  const StreamPool::Place at = pool.add_indices(m.indices, short_indices ? 2 : 4);
  const int indices = glb.add_accessor(at.view, short_indices ? gltf::kUnsignedShort : gltf::kUnsignedInt, false,
                                       m.indices.size(), "SCALAR", {}, {}, at.byte_offset);
  return {{"attributes", attributes}, {"indices", indices}, {"mode", 4}};
}

}  // namespace cellbake
