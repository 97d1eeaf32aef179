// Chunks merged into one mesh for the group tiers of the far field's level of
// detail (see chunk_groups.h).
#include "stages/chunk_groups.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>

namespace cellbake {
namespace {

// A merged vertex: every attribute, compared as bytes when welding.
struct MergedVertex {
  Vec3f position;
  Rgba8 color;
  Uv uv;
  Vec3f normal;
};

Vec3f face_normal(const Chunk& c, std::size_t t) {
  const Vec3d a = c.world(c.indices[3 * t]), b = c.world(c.indices[3 * t + 1]), d = c.world(c.indices[3 * t + 2]);
  const Vec3d n = cross(b - a, d - a);
  const double len = length(n);
  if (!(len > 0) || !std::isfinite(len)) return {};
  return {float(n.x / len), float(n.y / len), float(n.z / len)};
}

}  // namespace

Chunk merge_chunks(std::span<const Chunk* const> members, std::int64_t id, double weld) {
  if (members.empty()) throw std::invalid_argument("merge_chunks: no members");
  if (!(weld > 0) || !std::isfinite(weld)) throw std::invalid_argument("merge_chunks: weld must be finite and > 0");
  bool any_uvs = false, any_normals = false, any_materials = false;
  Chunk out;
  out.id = id;
  for (const Chunk* m : members) {
    if (!m) throw std::invalid_argument("merge_chunks: a null member");
    for (std::uint32_t i : m->indices)
      if (i >= m->positions.size())
        throw std::invalid_argument("merge_chunks: chunk " + std::to_string(m->id) + " indexes past its vertices");
    any_uvs = any_uvs || !m->uvs.empty();
    any_normals = any_normals || !m->normals.empty();
    any_materials = any_materials || !m->materials.empty();
    out.bounds.expand(m->bounds);
  }
  out.origin = out.bounds.empty() ? Vec3d{} : out.bounds.center();
  std::vector<MergedVertex> vertices;
  std::unordered_map<std::string_view, std::uint32_t> index_of;
  // Keys point into `keys`, which never reallocates (reserved for every corner).
  std::size_t corners = 0;
  for (const Chunk* m : members) corners += m->indices.size();
  std::vector<MergedVertex> keys;
  keys.reserve(corners);
  const auto add = [&](const MergedVertex& v) {
    keys.push_back(v);
    const std::string_view key(reinterpret_cast<const char*>(&keys.back()), sizeof(MergedVertex));
    const auto [it, added] = index_of.try_emplace(key, std::uint32_t(vertices.size()));
    if (added) vertices.push_back(v);
    return it->second;
  };
  const auto snap = [&](const Vec3d& world) {
    // + 0.0f: a coordinate rounding to -0 and one to +0 are one place.
    const auto axis = [&](double w, double o) { return float(std::nearbyint((w - o) / weld) * weld) + 0.0f; };
    return Vec3f{axis(world.x, out.origin.x), axis(world.y, out.origin.y), axis(world.z, out.origin.z)};
  };
  for (const Chunk* m : members) {
    const bool flat = any_normals && m->normals.empty();  // corners of their own with the face normal
    for (std::size_t t = 0; t < m->triangle_count(); ++t) {
      const Vec3f fn = flat ? face_normal(*m, t) : Vec3f{};
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t i = m->indices[3 * t + std::size_t(k)];
        MergedVertex v;
        std::memset(&v, 0, sizeof v);  // padding compares as bytes
        v.position = snap(m->world(i));
        v.color = m->colors.empty() ? Rgba8{} : m->colors[i];
        if (!m->uvs.empty()) v.uv = m->uvs[i];
        v.normal = flat ? fn : m->normals.empty() ? Vec3f{} : m->normals[i];
        out.indices.push_back(add(v));
      }
      if (any_materials) out.materials.push_back(m->materials.empty() ? 0 : m->materials[t]);
    }
  }
  out.positions.reserve(vertices.size());
  for (const MergedVertex& v : vertices) {
    out.positions.push_back(v.position);
    out.colors.push_back(v.color);
    if (any_uvs) out.uvs.push_back(v.uv);
    if (any_normals) out.normals.push_back(v.normal);
  }
  return out;
}

}  // namespace cellbake
