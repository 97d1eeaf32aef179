#include "stages/chunk_subset.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace cellbake {

Chunk chunk_subset(const Chunk& chunk, std::span<const std::uint32_t> triangles) {
  Chunk out;
  out.id = chunk.id;
  out.origin = chunk.origin;
  constexpr std::uint32_t kUnused = ~std::uint32_t{0};
  std::vector<std::uint32_t> remap(chunk.positions.size(), kUnused);
  std::uint32_t previous = 0;
  for (std::size_t k = 0; k < triangles.size(); ++k) {
    const std::uint32_t t = triangles[k];
    if (t >= chunk.triangle_count() || (k > 0 && t <= previous))
      throw std::invalid_argument("chunk_subset: chunk " + std::to_string(chunk.id) +
                                  ": triangle list not ascending or out of range");
    previous = t;
    for (int c = 0; c < 3; ++c) remap[chunk.indices[3 * std::size_t(t) + std::size_t(c)]] = 0;
  }
  const bool uvs = !chunk.uvs.empty(), normals = !chunk.normals.empty();
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] == kUnused) continue;
    remap[v] = next++;
    out.positions.push_back(chunk.positions[v]);
    out.colors.push_back(chunk.colors[v]);
    if (uvs) out.uvs.push_back(chunk.uvs[v]);
    if (normals) out.normals.push_back(chunk.normals[v]);
    out.bounds.expand(chunk.world(std::uint32_t(v)));
  }
  out.indices.reserve(3 * triangles.size());
  for (std::uint32_t t : triangles) {
    for (int c = 0; c < 3; ++c) out.indices.push_back(remap[chunk.indices[3 * std::size_t(t) + std::size_t(c)]]);
    if (!chunk.materials.empty()) out.materials.push_back(chunk.materials[t]);
  }
  return out;
}

}  // namespace cellbake
