// Plain geometry types shared by every stage: double-precision world vectors,
// boxes, colours and triangle meshes. No behaviour beyond small inline math.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace cellbake {

struct Vec3d {
  double x = 0, y = 0, z = 0;
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  friend Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3d operator*(Vec3d a, double s) { return {a.x * s, a.y * s, a.z * s}; }
  friend Vec3d operator*(double s, Vec3d a) { return a * s; }
  friend bool operator==(const Vec3d&, const Vec3d&) = default;
};

struct Vec3f {
  float x = 0, y = 0, z = 0;
  friend bool operator==(const Vec3f&, const Vec3f&) = default;
};

inline double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec3d a) { return std::sqrt(dot(a, a)); }
inline bool is_finite(Vec3d a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }

// Axis-aligned box. A default-constructed box is empty (lo > hi) and grows with expand().
struct Box3d {
  Vec3d lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity()};
  Vec3d hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           -std::numeric_limits<double>::infinity()};

  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void expand(Vec3d p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void expand(const Box3d& b) {
    if (b.empty()) return;
    expand(b.lo);
    expand(b.hi);
  }
  Vec3d center() const { return (lo + hi) * 0.5; }
  Vec3d extent() const { return hi - lo; }
  bool contains(const Box3d& b) const {
    return b.lo.x >= lo.x && b.lo.y >= lo.y && b.lo.z >= lo.z && b.hi.x <= hi.x && b.hi.y <= hi.y &&
           b.hi.z <= hi.z;
  }
  // b lies in this box's open interior (false when either is empty).
  bool strictly_contains(const Box3d& b) const {
    return !empty() && !b.empty() && b.lo.x > lo.x && b.lo.y > lo.y && b.lo.z > lo.z && b.hi.x < hi.x &&
           b.hi.y < hi.y && b.hi.z < hi.z;
  }
  bool overlaps(const Box3d& b) const {
    return !(b.hi.x < lo.x || b.lo.x > hi.x || b.hi.y < lo.y || b.lo.y > hi.y || b.hi.z < lo.z || b.lo.z > hi.z);
  }
  static Box3d cube(Vec3d c, double half) { return {{c.x - half, c.y - half, c.z - half}, {c.x + half, c.y + half, c.z + half}}; }
  // The distance from `p` to the box's nearest point (0 inside it).
  double distance_to(const Vec3d& p) const {
    const Vec3d nearest{std::clamp(p.x, lo.x, hi.x), std::clamp(p.y, lo.y, hi.y), std::clamp(p.z, lo.z, hi.z)};
    const Vec3d d{nearest.x - p.x, nearest.y - p.y, nearest.z - p.z};
    return std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  }
  friend bool operator==(const Box3d&, const Box3d&) = default;
};

struct Rgba8 {
  std::uint8_t r = 200, g = 200, b = 200, a = 255;
  friend bool operator==(const Rgba8&, const Rgba8&) = default;
};

struct Uv {
  float u = 0, v = 0;
  friend bool operator==(const Uv&, const Uv&) = default;
};

// One triangle with world positions and per-corner attributes: the record that
// readers and generators emit and ingest consumes.
struct Triangle {
  std::array<Vec3d, 3> p;
  std::array<Rgba8, 3> color;
  std::array<Uv, 3> uv;       // meaningful only when the source had texcoords
  std::array<Vec3f, 3> normal;  // unit per-corner normals; meaningful only when has_normals
  bool has_normals = false;     // the source gave normals (OBJ vn, PLY nx ny nz, assimp)
  std::uint32_t material = 0;  // index into the model's material table (0 = default)
};

// An indexed triangle mesh in world coordinates (double). Colours and uvs are
// either empty or one per position.
struct TriangleMesh {
  std::vector<Vec3d> positions;
  std::vector<Rgba8> colors;
  std::vector<Uv> uvs;
  std::vector<std::uint32_t> indices;  // three per triangle
  std::size_t triangle_count() const { return indices.size() / 3; }
};

// A material as imported: a base colour multiplied into vertex colours at
// ingest, and an optional diffuse / base-colour texture. `texture` is the path
// or reference the source gave (kept for messages); `texture_id` names the
// image stored in the geometry store (0 = none: untextured, or the file could
// not be read). Colours of textured triangles are vertex colour x texel.
struct Material {
  std::string name;
  Rgba8 color{255, 255, 255, 255};
  std::string texture;
  std::int64_t texture_id = 0;
  bool alpha_test = false;  // fragments whose texel alpha is below 0.5 are dropped
  friend bool operator==(const Material&, const Material&) = default;
};

// A chunk of spatially coherent triangles: positions are float32 relative to a
// double-precision origin so far-from-origin models keep their precision.
struct Chunk {
  std::int64_t id = 0;
  Vec3d origin;
  Box3d bounds;  // world bounds of the chunk's triangles
  std::vector<Vec3f> positions;
  std::vector<Rgba8> colors;  // one per position
  std::vector<Uv> uvs;        // empty or one per position
  std::vector<Vec3f> normals; // empty (flat face normals) or one unit normal per position
  std::vector<std::uint32_t> indices;
  std::vector<std::uint32_t> materials;  // empty (all 0) or one per triangle
  std::size_t triangle_count() const { return indices.size() / 3; }
  Vec3d world(std::uint32_t vertex) const {
    const Vec3f& p = positions[vertex];
    return {origin.x + p.x, origin.y + p.y, origin.z + p.z};
  }
};

}  // namespace cellbake
