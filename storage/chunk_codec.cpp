#include "storage/chunk_codec.h"

#include <meshoptimizer.h>

#include "stages/normal_packing.h"

#include <array>
#include <cstring>
#include <stdexcept>

namespace cellbake {
namespace {

constexpr std::uint32_t kMagic = 0x4B434243;  // "CBCK" little-endian
constexpr std::uint16_t kVersion = 1;
constexpr std::uint16_t kHasUvs = 1;
constexpr std::uint16_t kHasMaterials = 2;
constexpr std::uint16_t kHasNormals = 4;
constexpr std::uint32_t kMaxVertices = 1u << 24;

struct PackedVertex {
  float x, y, z;
  std::uint8_t r, g, b, a;
};
struct PackedVertexUv {
  float x, y, z;
  std::uint8_t r, g, b, a;
  float u, v;
};

template <typename T>
void put(std::vector<std::uint8_t>& out, T value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <typename T>
  T get(const char* what) {
    T value;
    need(sizeof(T), what);
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  const std::uint8_t* take(std::size_t n, const char* what) {
    need(n, what);
    const std::uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  bool at_end() const { return pos_ == size_; }

 private:
  void need(std::size_t n, const char* what) const {
    if (n > size_ - pos_) throw std::runtime_error(std::string("chunk blob: truncated in ") + what);
  }
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

template <typename V>
std::vector<std::uint8_t> encode_vertices(const std::vector<V>& v) {
  std::vector<std::uint8_t> buf(meshopt_encodeVertexBufferBound(v.size(), sizeof(V)));
  buf.resize(meshopt_encodeVertexBuffer(buf.data(), buf.size(), v.data(), v.size(), sizeof(V)));
  return buf;
}

}  // namespace

std::vector<std::uint8_t> encode_chunk_blob(const Chunk& chunk) {
  const std::size_t nv = chunk.positions.size();
  if (chunk.colors.size() != nv) throw std::invalid_argument("encode_chunk_blob: colours must match positions");
  if (!chunk.uvs.empty() && chunk.uvs.size() != nv) throw std::invalid_argument("encode_chunk_blob: uv count");
  if (chunk.indices.size() % 3 != 0) throw std::invalid_argument("encode_chunk_blob: index count not a multiple of 3");
  if (nv > kMaxVertices) throw std::invalid_argument("encode_chunk_blob: too many vertices");
  const bool has_uvs = !chunk.uvs.empty();
  const bool has_materials = !chunk.materials.empty();
  const bool has_normals = !chunk.normals.empty();
  if (has_normals && chunk.normals.size() != nv) throw std::invalid_argument("encode_chunk_blob: normal count");

  std::vector<std::uint8_t> vertex_bytes;
  if (has_uvs) {
    std::vector<PackedVertexUv> v(nv);
    for (std::size_t i = 0; i < nv; ++i) {
      const auto& p = chunk.positions[i];
      const auto& c = chunk.colors[i];
      v[i] = {p.x, p.y, p.z, c.r, c.g, c.b, c.a, chunk.uvs[i].u, chunk.uvs[i].v};
    }
    vertex_bytes = encode_vertices(v);
  } else {
    std::vector<PackedVertex> v(nv);
    for (std::size_t i = 0; i < nv; ++i) {
      const auto& p = chunk.positions[i];
      const auto& c = chunk.colors[i];
      v[i] = {p.x, p.y, p.z, c.r, c.g, c.b, c.a};
    }
    vertex_bytes = encode_vertices(v);
  }
  std::vector<std::uint8_t> index_bytes(meshopt_encodeIndexBufferBound(chunk.indices.size(), nv));
  index_bytes.resize(
      meshopt_encodeIndexBuffer(index_bytes.data(), index_bytes.size(), chunk.indices.data(), chunk.indices.size()));

  std::vector<std::uint8_t> normal_bytes;
  if (has_normals) {
    std::vector<std::array<std::int16_t, 2>> packed(nv);
    for (std::size_t i = 0; i < nv; ++i) packed[i] = pack_normal_oct16(chunk.normals[i]);
    normal_bytes = encode_vertices(packed);
  }

  std::vector<std::uint8_t> out;
  out.reserve(36 + vertex_bytes.size() + index_bytes.size() + normal_bytes.size() +
              (has_materials ? chunk.materials.size() * 4 : 0));
  put<std::uint32_t>(out, kMagic);
  put<std::uint16_t>(out, kVersion);
  put<std::uint16_t>(out, static_cast<std::uint16_t>((has_uvs ? kHasUvs : 0) | (has_materials ? kHasMaterials : 0) |
                                                     (has_normals ? kHasNormals : 0)));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(nv));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(chunk.indices.size()));
  put<std::uint32_t>(out, static_cast<std::uint32_t>(vertex_bytes.size()));
  out.insert(out.end(), vertex_bytes.begin(), vertex_bytes.end());
  put<std::uint32_t>(out, static_cast<std::uint32_t>(index_bytes.size()));
  out.insert(out.end(), index_bytes.begin(), index_bytes.end());
  if (has_materials) {
    if (chunk.materials.size() != chunk.indices.size() / 3)
      throw std::invalid_argument("encode_chunk_blob: material count must match triangles");
    for (std::uint32_t m : chunk.materials) put<std::uint32_t>(out, m);
  }
  if (has_normals) {
    put<std::uint32_t>(out, static_cast<std::uint32_t>(normal_bytes.size()));
    out.insert(out.end(), normal_bytes.begin(), normal_bytes.end());
  }
  return out;
}

void decode_chunk_blob(const std::uint8_t* data, std::size_t size, Chunk& chunk) {
  if (!data && size) throw std::runtime_error("chunk blob: null data");
  Reader in(data, size);
  if (in.get<std::uint32_t>("magic") != kMagic) throw std::runtime_error("chunk blob: bad magic");
  const auto version = in.get<std::uint16_t>("version");
  if (version != kVersion) throw std::runtime_error("chunk blob: unsupported version " + std::to_string(version));
  const auto flags = in.get<std::uint16_t>("flags");
  if (flags & ~(kHasUvs | kHasMaterials | kHasNormals)) throw std::runtime_error("chunk blob: unknown flags");
  const auto nv = in.get<std::uint32_t>("vertex count");
  const auto ni = in.get<std::uint32_t>("index count");
  if (nv > kMaxVertices) throw std::runtime_error("chunk blob: vertex count out of range");
  if (ni % 3 != 0 || ni > 3u * kMaxVertices * 4u) throw std::runtime_error("chunk blob: bad index count");
  if ((nv == 0) != (ni == 0)) throw std::runtime_error("chunk blob: vertices without triangles or vice versa");
  const auto vbytes = in.get<std::uint32_t>("vertex data size");
  const std::uint8_t* vdata = in.take(vbytes, "vertex data");
  const auto ibytes = in.get<std::uint32_t>("index data size");
  const std::uint8_t* idata = in.take(ibytes, "index data");

  const bool has_uvs = flags & kHasUvs;
  // Lower bounds of meshoptimizer's codecs, checked before anything is sized
  // by the counts (a 30-byte blob could otherwise claim 2^24 vertices): the
  // vertex codec spends at least one header byte per 64 vertices per vertex
  // byte, the index codec at least one code byte per triangle.
  const std::size_t vertex_size = has_uvs ? sizeof(PackedVertexUv) : sizeof(PackedVertex);
  if (std::uint64_t(vbytes) * 64 < std::uint64_t(nv) * vertex_size)
    throw std::runtime_error("chunk blob: vertex data too short for " + std::to_string(nv) + " vertices");
  if (ibytes < ni / 3) throw std::runtime_error("chunk blob: index data too short for " + std::to_string(ni) + " indices");
  chunk.positions.resize(nv);
  chunk.colors.resize(nv);
  chunk.uvs.clear();
  if (has_uvs) {
    std::vector<PackedVertexUv> v(nv);
    if (nv && meshopt_decodeVertexBuffer(v.data(), nv, sizeof(PackedVertexUv), vdata, vbytes) != 0)
      throw std::runtime_error("chunk blob: corrupt vertex data");
    chunk.uvs.resize(nv);
    for (std::size_t i = 0; i < nv; ++i) {
      chunk.positions[i] = {v[i].x, v[i].y, v[i].z};
      chunk.colors[i] = {v[i].r, v[i].g, v[i].b, v[i].a};
      chunk.uvs[i] = {v[i].u, v[i].v};
    }
  } else {
    std::vector<PackedVertex> v(nv);
    if (nv && meshopt_decodeVertexBuffer(v.data(), nv, sizeof(PackedVertex), vdata, vbytes) != 0)
      throw std::runtime_error("chunk blob: corrupt vertex data");
    for (std::size_t i = 0; i < nv; ++i) {
      chunk.positions[i] = {v[i].x, v[i].y, v[i].z};
      chunk.colors[i] = {v[i].r, v[i].g, v[i].b, v[i].a};
    }
  }
  for (const auto& p : chunk.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::runtime_error("chunk blob: non-finite position");
  chunk.indices.resize(ni);
  if (ni && meshopt_decodeIndexBuffer(chunk.indices.data(), ni, sizeof(std::uint32_t), idata, ibytes) != 0)
    throw std::runtime_error("chunk blob: corrupt index data");
  for (std::uint32_t i : chunk.indices)
    if (i >= nv) throw std::runtime_error("chunk blob: index out of range");
  chunk.materials.clear();
  if (flags & kHasMaterials) {
    const std::uint8_t* m = in.take(std::size_t(ni / 3) * 4, "materials");
    chunk.materials.resize(ni / 3);
    if (!chunk.materials.empty()) std::memcpy(chunk.materials.data(), m, chunk.materials.size() * 4);
  }
  chunk.normals.clear();
  if (flags & kHasNormals) {
    const auto nbytes = in.get<std::uint32_t>("normal data size");
    const std::uint8_t* ndata = in.take(nbytes, "normal data");
    std::vector<std::array<std::int16_t, 2>> packed(nv);
    if (nv && meshopt_decodeVertexBuffer(packed.data(), nv, sizeof(packed[0]), ndata, nbytes) != 0)
      throw std::runtime_error("chunk blob: corrupt normal data");
    chunk.normals.resize(nv);
    for (std::size_t i = 0; i < nv; ++i) chunk.normals[i] = unpack_normal_oct16(packed[i]);
  }
  if (!in.at_end()) throw std::runtime_error("chunk blob: trailing bytes");
}

}  // namespace cellbake
