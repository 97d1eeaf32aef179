// Stage `encode`, grid face meshes (blob version 2). See encode_grid_mesh.h.
//
// Touma & Gotsman 1998, "Triangle Mesh Compression" (parallelogram
// prediction of a new vertex from the triangle across the edge it is attached
// to); connectivity through meshoptimizer's index codec (Kapoulkine,
// meshoptimizer 0.18); residual streams entropy-coded with zstd (Collet,
// RFC 8878). Depth is quantised as log(z) in steps of 2 log(1 + e), so the
// relative error is at most e everywhere, in the relative units the
// simplifier's depth bound uses. Predictions are integer-only, so the encoder
// and any decoder agree bit for bit.
#include "stages/encode/encode_grid_mesh.h"
#include "stages/little_endian.h"

#include <meshoptimizer.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

using little_endian::put_u32;
using little_endian::get_u32;
using little_endian::put_f64;
using little_endian::get_f64;


constexpr std::array<std::uint8_t, 4> kMagic = {'C', 'B', 'F', 'M'};
constexpr std::size_t kHeaderSize = 48;
constexpr std::uint8_t kFlagZstd = 1;
constexpr std::uint32_t kMaxFaceSize = 16384;
constexpr std::int64_t kMaxQRange = std::int64_t{1} << 24;

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("face mesh blob: " + what); }


// Layout: magic[4] version face flags reserved | face_size vertex_count
// index_count (u32) | log_step (f64) | q_min (i32) q_range | index_bytes
// ij_bytes q_bytes (u32) | payload: the three streams, zstd frame or raw.
struct Header {
  std::uint8_t face = 0, flags = 0;
  std::uint32_t face_size = 0, vertex_count = 0, index_count = 0;
  double log_step = 0;
  std::int32_t q_min = 0;
  std::uint32_t q_range = 0;
  std::uint32_t index_bytes = 0, ij_bytes = 0, q_bytes = 0;
  std::uint64_t raw_bytes() const { return std::uint64_t{index_bytes} + ij_bytes + q_bytes; }
};

void write_header(std::uint8_t* out, const Header& h) {
  std::memcpy(out, kMagic.data(), 4);
  out[4] = kGridMeshVersion;
  out[5] = h.face;
  out[6] = h.flags;
  out[7] = 0;
  put_u32(out + 8, h.face_size);
  put_u32(out + 12, h.vertex_count);
  put_u32(out + 16, h.index_count);
  put_f64(out + 20, h.log_step);
  put_u32(out + 28, static_cast<std::uint32_t>(h.q_min));
  put_u32(out + 32, h.q_range);
  put_u32(out + 36, h.index_bytes);
  put_u32(out + 40, h.ij_bytes);
  put_u32(out + 44, h.q_bytes);
}

Header read_header(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size < kHeaderSize)
    fail(std::to_string(size) + " bytes, shorter than the " + std::to_string(kHeaderSize) + "-byte v2 header");
  if (std::memcmp(data, kMagic.data(), 4) != 0) fail("bad magic");
  if (data[4] != kGridMeshVersion) fail("unsupported version " + std::to_string(data[4]));
  Header h;
  h.face = data[5];
  h.flags = data[6];
  if (h.face >= kCubeFaces) fail("face " + std::to_string(h.face) + " outside 0..5");
  if ((h.flags & ~kFlagZstd) != 0 || data[7] != 0) fail("unknown flags");
  h.face_size = get_u32(data + 8);
  h.vertex_count = get_u32(data + 12);
  h.index_count = get_u32(data + 16);
  h.log_step = get_f64(data + 20);
  h.q_min = static_cast<std::int32_t>(get_u32(data + 28));
  h.q_range = get_u32(data + 32);
  h.index_bytes = get_u32(data + 36);
  h.ij_bytes = get_u32(data + 40);
  h.q_bytes = get_u32(data + 44);
  if (h.face_size < 1 || h.face_size > kMaxFaceSize) fail("face size " + std::to_string(h.face_size));
  if (!(h.log_step > 0 && h.log_step <= 1)) fail("bad depth step");
  if (h.q_range > kMaxQRange) fail("depth range " + std::to_string(h.q_range) + " too large");
  const double lo = h.q_min * h.log_step, hi = (double(h.q_min) + h.q_range) * h.log_step;
  if (!(lo > -600 && hi < 600)) fail("depth range outside float");
  if (h.index_count % 3 != 0) fail("index count " + std::to_string(h.index_count) + " is not a multiple of 3");
  if (h.vertex_count > h.index_count) fail("more vertices than indices");
  if ((h.vertex_count == 0) != (h.index_count == 0)) fail("vertices without indices or indices without vertices");
  // Each vertex costs at least one byte per residual; the index codec at
  // least one byte per triangle plus a 17-byte frame.
  if (std::uint64_t{h.vertex_count} * 2 > h.ij_bytes || h.vertex_count > h.q_bytes)
    fail("vertex count too large for its streams");
  if (h.index_count > 0 && std::uint64_t{h.index_count} / 3 + 17 > h.index_bytes)
    fail("index count too large for its stream");
  if (h.index_count == 0 && h.raw_bytes() != 0) fail("stream data without a mesh");
  return h;
}

// ------------------------------------------------------------ residuals

std::uint32_t zigzag(std::int64_t v) {
  return static_cast<std::uint32_t>((static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63));
}
std::int64_t unzigzag(std::uint32_t u) { return static_cast<std::int64_t>(u >> 1) ^ -static_cast<std::int64_t>(u & 1); }

void put_varint(std::vector<std::uint8_t>& out, std::uint32_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

struct Reader {
  const std::uint8_t* p;
  const std::uint8_t* end;
  std::uint32_t varint() {
    std::uint32_t v = 0;
    for (int shift = 0; shift < 35; shift += 7) {
      if (p == end) fail("residual stream ends early");
      const std::uint8_t b = *p++;
      v |= std::uint32_t(b & 0x7f) << shift;
      if ((b & 0x80) == 0) return v;
    }
    fail("residual varint too long");
  }
};

// ------------------------------------------------------- the shared walk

// Open-addressing map from an undirected edge to the third vertex of the
// first triangle that used it (parallelogram partner).
class EdgeMap {
 public:
  explicit EdgeMap(std::size_t edges) {
    std::size_t n = 16;
    while (n < 2 * edges) n *= 2;
    keys_.assign(n, kEmpty);
    values_.resize(n);
  }
  void insert(std::uint32_t a, std::uint32_t b, std::uint32_t third) {
    const std::uint64_t key = make_key(a, b);
    for (std::size_t s = slot(key);; s = (s + 1) & (keys_.size() - 1)) {
      if (keys_[s] == key) return;
      if (keys_[s] == kEmpty) {
        keys_[s] = key, values_[s] = third;
        return;
      }
    }
  }
  bool find(std::uint32_t a, std::uint32_t b, std::uint32_t& third) const {
    const std::uint64_t key = make_key(a, b);
    for (std::size_t s = slot(key);; s = (s + 1) & (keys_.size() - 1)) {
      if (keys_[s] == key) return third = values_[s], true;
      if (keys_[s] == kEmpty) return false;
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  static std::uint64_t make_key(std::uint32_t a, std::uint32_t b) {
    return a < b ? (std::uint64_t{a} << 32 | b) : (std::uint64_t{b} << 32 | a);
  }
  std::size_t slot(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & (keys_.size() - 1);
  }
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> values_;
};

struct GridVertex {
  std::int64_t i = 0, j = 0, q = 0;
};

std::int64_t div_round(std::int64_t num, std::int64_t den) {
  if (den < 0) num = -num, den = -den;
  const std::int64_t twice = 2 * num + den, d2 = 2 * den;  // floor((num + den/2) / den)
  return twice >= 0 ? twice / d2 : -((-twice + d2 - 1) / d2);
}

// Visits the triangles in order; each vertex met for the first time is
// predicted from the triangle's known corners (parallelogram across a known
// edge, else the edge midpoint, else a known corner, else the previous new
// vertex) and `code(v, prediction, slot)` turns the prediction into the
// vertex (the encoder writes the residual, the decoder reads it). Depth is
// predicted after (i, j) are known, from the plane through the three
// parallelogram vertices. Throws (the blob error) for a vertex off the face
// or outside the depth range, or one no triangle uses.
template <class Code>
void walk(const std::vector<std::uint32_t>& indices, std::vector<GridVertex>& vertices, std::int64_t face_size,
          std::int64_t q_range, Code&& code) {
  std::vector<std::uint8_t> seen(vertices.size(), 0);
  EdgeMap edges(indices.size());
  GridVertex last{face_size / 2, face_size / 2, q_range / 2};
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const std::uint32_t tri[3] = {indices[t], indices[t + 1], indices[t + 2]};
    for (int s = 0; s < 3; ++s) {
      const std::uint32_t v = tri[s];
      if (seen[v]) continue;
      const std::uint32_t a = tri[(s + 1) % 3], b = tri[(s + 2) % 3];
      GridVertex pred = last;
      std::uint32_t d = 0;
      const bool has_a = seen[a] != 0, has_b = seen[b] != 0;
      const bool parallelogram = has_a && has_b && edges.find(a, b, d);
      const GridVertex &A = vertices[a], &B = vertices[b];
      if (parallelogram) {
        const GridVertex& D = vertices[d];
        pred.i = std::clamp<std::int64_t>(A.i + B.i - D.i, 0, face_size);
        pred.j = std::clamp<std::int64_t>(A.j + B.j - D.j, 0, face_size);
      } else if (has_a && has_b) {
        pred = {(A.i + B.i) / 2, (A.j + B.j) / 2, (A.q + B.q) / 2};
      } else if (has_a) {
        pred = A;
      } else if (has_b) {
        pred = B;
      }
      GridVertex out;
      out.i = code.ij(v, pred.i);
      out.j = code.ij(v, pred.j);
      if (out.i < 0 || out.i > face_size || out.j < 0 || out.j > face_size)
        fail("vertex " + std::to_string(v) + " off the face");
      if (parallelogram) {
        const GridVertex& D = vertices[d];
        const std::int64_t ui = B.i - A.i, uj = B.j - A.j, uq = B.q - A.q;
        const std::int64_t wi = D.i - A.i, wj = D.j - A.j, wq = D.q - A.q;
        const std::int64_t ni = uj * wq - uq * wj, nj = uq * wi - ui * wq, nq = ui * wj - uj * wi;
        pred.q = nq != 0 ? A.q - div_round(ni * (out.i - A.i) + nj * (out.j - A.j), nq) : (A.q + B.q) / 2;
        pred.q = std::clamp<std::int64_t>(pred.q, 0, q_range);
      }
      out.q = code.q(v, pred.q);
      if (out.q < 0 || out.q > q_range) fail("vertex " + std::to_string(v) + " depth outside its range");
      vertices[v] = out;
      seen[v] = 1;
      last = out;
    }
    edges.insert(tri[0], tri[1], tri[2]);
    edges.insert(tri[1], tri[2], tri[0]);
    edges.insert(tri[2], tri[0], tri[1]);
  }
  for (std::size_t v = 0; v < seen.size(); ++v)
    if (!seen[v]) fail("vertex " + std::to_string(v) + " is not used by any triangle");
}

struct EncodeCoder {
  const std::vector<GridVertex>* truth;
  std::vector<std::uint8_t> ij_out, q_out;
  int axis = 0;
  std::int64_t ij(std::uint32_t v, std::int64_t pred) {
    const std::int64_t value = axis == 0 ? (*truth)[v].i : (*truth)[v].j;
    axis ^= 1;
    put_varint(ij_out, zigzag(value - pred));
    return value;
  }
  std::int64_t q(std::uint32_t v, std::int64_t pred) {
    put_varint(q_out, zigzag((*truth)[v].q - pred));
    return (*truth)[v].q;
  }
};

struct DecodeCoder {
  Reader ij_in, q_in;
  std::int64_t ij(std::uint32_t, std::int64_t pred) { return pred + unzigzag(ij_in.varint()); }
  std::int64_t q(std::uint32_t, std::int64_t pred) { return pred + unzigzag(q_in.varint()); }
};

// The pixel-ray direction through corner (i, j) scaled by n, as
// build_depth_meshes forms it (integers, exact in double).
std::array<double, 3> corner_direction(const FaceBasis& b, std::int64_t i, std::int64_t j, std::int64_t n) {
  const double f = double(n), r = double(2 * i - n), u = double(n - 2 * j);
  return {b.forward.x * f + b.right.x * r + b.up.x * u, b.forward.y * f + b.right.y * r + b.up.y * u,
          b.forward.z * f + b.right.z * r + b.up.z * u};
}

}  // namespace

std::optional<std::vector<std::uint8_t>> encode_grid_face_mesh(const FaceMesh& mesh, int face, int face_size,
                                                               double depth_error_relative, int zstd_level) {
  if (face < 0 || face >= kCubeFaces || face_size < 1 || std::uint32_t(face_size) > kMaxFaceSize ||
      !(depth_error_relative > 0 && depth_error_relative < 0.5) || mesh.uvs.size() != mesh.positions.size() ||
      mesh.positions.size() > std::numeric_limits<std::uint32_t>::max() / 4)
    return std::nullopt;
  const FaceBasis basis = cube_face_basis(face);
  const std::int64_t n = face_size;
  const double log_step = 2 * std::log1p(depth_error_relative);

  // Pixel corners and log depths of the input vertices; any vertex off its
  // corner ray means this is not a grid mesh.
  std::vector<GridVertex> grid(mesh.positions.size());
  std::int64_t q_lo = std::numeric_limits<std::int64_t>::max(), q_hi = std::numeric_limits<std::int64_t>::min();
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const double su = double(mesh.uvs[v].u) * double(n), sv = double(mesh.uvs[v].v) * double(n);
    const double ri = std::nearbyint(su), rj = std::nearbyint(sv);
    if (!(std::fabs(su - ri) <= 1e-3 && std::fabs(sv - rj) <= 1e-3 && ri >= 0 && ri <= double(n) && rj >= 0 &&
          rj <= double(n)))
      return std::nullopt;
    const Vec3f& p = mesh.positions[v];
    const double z = basis.forward.x * p.x + basis.forward.y * p.y + basis.forward.z * p.z;
    if (!(z > 0 && std::isfinite(z))) return std::nullopt;
    const std::int64_t i = std::int64_t(ri), j = std::int64_t(rj);
    const std::array<double, 3> dir = corner_direction(basis, i, j, n);
    const double dx = p.x - dir[0] * z / double(n), dy = p.y - dir[1] * z / double(n),
                 dz = p.z - dir[2] * z / double(n);
    const double len = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
    if (std::sqrt(dx * dx + dy * dy + dz * dz) > 1e-5 * len) return std::nullopt;
    const double lq = std::nearbyint(std::log(z) / log_step);
    if (!(std::fabs(lq) < 1e9)) return std::nullopt;
    grid[v] = {i, j, std::int64_t(lq)};
    q_lo = std::min(q_lo, grid[v].q), q_hi = std::max(q_hi, grid[v].q);
  }
  if (!mesh.positions.empty()) {
    if (q_hi - q_lo > kMaxQRange || q_lo < std::numeric_limits<std::int32_t>::min() ||
        q_lo > std::numeric_limits<std::int32_t>::max() || !(q_lo * log_step > -600 && q_hi * log_step < 600))
      return std::nullopt;
    for (GridVertex& g : grid) g.q -= q_lo;
  }

  Header h;
  h.face = static_cast<std::uint8_t>(face);
  h.face_size = static_cast<std::uint32_t>(face_size);
  h.log_step = log_step;
  std::vector<std::uint8_t> payload;
  if (!mesh.indices.empty()) {
    h.q_min = static_cast<std::int32_t>(q_lo);
    h.q_range = static_cast<std::uint32_t>(q_hi - q_lo);
    // Vertex-cache order, vertices renumbered by first use (unused ones dropped).
    const std::size_t count = mesh.positions.size();
    std::vector<std::uint32_t> cached(mesh.indices.size()), remap(count), indices(mesh.indices.size());
    meshopt_optimizeVertexCache(cached.data(), mesh.indices.data(), mesh.indices.size(), count);
    const std::size_t used = meshopt_optimizeVertexFetchRemap(remap.data(), cached.data(), cached.size(), count);
    meshopt_remapIndexBuffer(indices.data(), cached.data(), cached.size(), remap.data());
    std::vector<GridVertex> ordered(used);
    for (std::size_t v = 0; v < count; ++v)
      if (remap[v] != ~0u) ordered[remap[v]] = grid[v];

    std::vector<std::uint8_t> index_stream(meshopt_encodeIndexBufferBound(indices.size(), used));
    index_stream.resize(
        meshopt_encodeIndexBuffer(index_stream.data(), index_stream.size(), indices.data(), indices.size()));
    if (index_stream.empty()) throw std::runtime_error("encode_face_mesh: index codec failed");
    // The decoder walks the triangles as the codec gives them back (corners may be rotated).
    std::vector<std::uint32_t> decoded(indices.size());
    if (meshopt_decodeIndexBuffer(decoded.data(), decoded.size(), sizeof(std::uint32_t), index_stream.data(),
                                  index_stream.size()) != 0)
      throw std::runtime_error("encode_face_mesh: index codec round trip failed");

    EncodeCoder coder{&ordered, {}, {}, 0};
    std::vector<GridVertex> walked(used);
    walk(decoded, walked, n, h.q_range, coder);
    h.vertex_count = static_cast<std::uint32_t>(used);
    h.index_count = static_cast<std::uint32_t>(indices.size());
    h.index_bytes = static_cast<std::uint32_t>(index_stream.size());
    h.ij_bytes = static_cast<std::uint32_t>(coder.ij_out.size());
    h.q_bytes = static_cast<std::uint32_t>(coder.q_out.size());
    payload = std::move(index_stream);
    payload.insert(payload.end(), coder.ij_out.begin(), coder.ij_out.end());
    payload.insert(payload.end(), coder.q_out.begin(), coder.q_out.end());

    std::vector<std::uint8_t> packed(ZSTD_compressBound(payload.size()));
    const std::size_t packed_size =
        ZSTD_compress(packed.data(), packed.size(), payload.data(), payload.size(), zstd_level);
    if (!ZSTD_isError(packed_size) && packed_size < payload.size() &&
        payload.size() <= 128 * std::uint64_t{packed_size} + 65536) {
      packed.resize(packed_size);
      payload = std::move(packed);
      h.flags = kFlagZstd;
    }
  }
  std::vector<std::uint8_t> blob(kHeaderSize + payload.size());
  write_header(blob.data(), h);
  std::copy(payload.begin(), payload.end(), blob.begin() + kHeaderSize);
  return blob;
}

FaceMesh decode_grid_face_mesh(const std::uint8_t* data, std::size_t size) {
  const Header h = read_header(data, size);
  FaceMesh mesh;
  const std::uint8_t* body = data + kHeaderSize;
  const std::size_t body_size = size - kHeaderSize;
  std::vector<std::uint8_t> unpacked;
  const std::uint8_t* raw = body;
  if (h.flags & kFlagZstd) {
    if (h.raw_bytes() > 128 * std::uint64_t{body_size} + 65536) fail("streams too large for the payload");
    const unsigned long long content = ZSTD_getFrameContentSize(body, body_size);
    if (content != h.raw_bytes()) fail("payload frame size does not match the streams");
    unpacked.resize(static_cast<std::size_t>(h.raw_bytes()));
    const std::size_t got = ZSTD_decompress(unpacked.data(), unpacked.size(), body, body_size);
    if (ZSTD_isError(got) || got != unpacked.size()) fail("payload does not decompress");
    raw = unpacked.data();
  } else if (h.raw_bytes() != body_size) {
    fail("stream sizes do not match the blob size " + std::to_string(size));
  }
  if (h.index_count == 0) return mesh;

  mesh.indices.resize(h.index_count);
  if (meshopt_decodeIndexBuffer(mesh.indices.data(), mesh.indices.size(), sizeof(std::uint32_t), raw,
                                h.index_bytes) != 0)
    fail("index stream does not decode");
  for (std::size_t i = 0; i < mesh.indices.size(); ++i)
    if (mesh.indices[i] >= h.vertex_count)
      fail("index " + std::to_string(i) + " = " + std::to_string(mesh.indices[i]) + " is past the " +
           std::to_string(h.vertex_count) + " vertices");

  std::vector<GridVertex> grid(h.vertex_count);
  const std::uint8_t* ij = raw + h.index_bytes;
  const std::uint8_t* q = ij + h.ij_bytes;
  DecodeCoder coder{{ij, ij + h.ij_bytes}, {q, q + h.q_bytes}};
  walk(mesh.indices, grid, h.face_size, h.q_range, coder);
  if (coder.ij_in.p != coder.ij_in.end || coder.q_in.p != coder.q_in.end) fail("residual streams too long");

  const FaceBasis basis = cube_face_basis(h.face);
  const std::int64_t n = h.face_size;
  const float inv_n = 1.0f / float(n);
  mesh.positions.resize(grid.size());
  mesh.uvs.resize(grid.size());
  for (std::size_t v = 0; v < grid.size(); ++v) {
    const GridVertex& g = grid[v];
    const double scale = std::exp((double(h.q_min) + double(g.q)) * h.log_step) / double(n);
    const std::array<double, 3> d = corner_direction(basis, g.i, g.j, n);
    mesh.positions[v] = {float(d[0] * scale), float(d[1] * scale), float(d[2] * scale)};
    mesh.uvs[v] = {float(g.i) * inv_n, float(g.j) * inv_n};
  }
  return mesh;
}

}  // namespace cellbake
