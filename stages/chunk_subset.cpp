#include "stages/chunk_subset.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cellbake {

Chunk chunk_subset(const Chunk& chunk, std::span<const std::uint32_t> triangles) {
  Chunk out;
  out.id = chunk.id;
  out.origin = chunk.origin;
  // Mark the vertices the triangles use, then copy them in order: one pass
  // over the triangles, one over the vertices, outputs sized up front (this
  // runs on the viewer's cell loader for every far piece).
  constexpr std::uint32_t kUnused = ~std::uint32_t{0};
  std::vector<std::uint32_t> remap(chunk.positions.size(), kUnused);
  const std::size_t triangle_count = chunk.triangle_count();
  const std::uint32_t* indices = chunk.indices.data();
  std::uint32_t previous = 0;
  for (std::size_t k = 0; k < triangles.size(); ++k) {
    const std::uint32_t t = triangles[k];
    if (t >= triangle_count || (k > 0 && t <= previous))
      throw std::invalid_argument("chunk_subset: chunk " + std::to_string(chunk.id) +
                                  ": triangle list not ascending or out of range");
    previous = t;
    const std::uint32_t* corner = indices + 3 * std::size_t(t);
    remap[corner[0]] = remap[corner[1]] = remap[corner[2]] = 0;
  }
  std::uint32_t used = 0;
  for (std::uint32_t& r : remap)
    if (r != kUnused) r = used++;
  const bool uvs = !chunk.uvs.empty(), normals = !chunk.normals.empty();
  out.positions.resize(used);
  out.colors.resize(used);
  if (uvs) out.uvs.resize(used);
  if (normals) out.normals.resize(used);
  // Bounds over the local float positions, then moved to the origin once:
  // adding the origin is monotone, so this is the box of the world positions.
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Vec3f lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  for (std::size_t v = 0; v < remap.size(); ++v) {
    const std::uint32_t to = remap[v];
    if (to == kUnused) continue;
    const Vec3f& p = chunk.positions[v];
    out.positions[to] = p;
    out.colors[to] = chunk.colors[v];
    if (uvs) out.uvs[to] = chunk.uvs[v];
    if (normals) out.normals[to] = chunk.normals[v];
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  if (used > 0) {
    out.bounds.expand(Vec3d{chunk.origin.x + lo.x, chunk.origin.y + lo.y, chunk.origin.z + lo.z});
    out.bounds.expand(Vec3d{chunk.origin.x + hi.x, chunk.origin.y + hi.y, chunk.origin.z + hi.z});
  }
  out.indices.resize(3 * triangles.size());
  std::uint32_t* to = out.indices.data();
  for (std::uint32_t t : triangles) {
    const std::uint32_t* corner = indices + 3 * std::size_t(t);
    *to++ = remap[corner[0]], *to++ = remap[corner[1]], *to++ = remap[corner[2]];
  }
  if (!chunk.materials.empty()) {
    out.materials.resize(triangles.size());
    for (std::size_t k = 0; k < triangles.size(); ++k) out.materials[k] = chunk.materials[triangles[k]];
  }
  return out;
}

}  // namespace cellbake
