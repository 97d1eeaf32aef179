// Some triangles of a chunk as a chunk of their own: the far field's exact
// geometry keeps only the triangles its samples saw (stages/far/far_choice.h).
#pragma once

#include <cstdint>
#include <span>

#include "stages/geometry.h"

namespace cellbake {

// The chunk made of `chunk`'s triangles `triangles` (ascending, each <
// triangle_count(); throws std::invalid_argument otherwise): the same id and
// origin, the vertices those triangles use (in their original order) with
// their colours, uvs and normals, the triangles' materials, and bounds
// recomputed from the kept vertices.
Chunk chunk_subset(const Chunk& chunk, std::span<const std::uint32_t> triangles);

}  // namespace cellbake
