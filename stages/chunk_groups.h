// Groups of neighbouring chunks merged into one mesh, the coarse tiers of a
// hierarchical level of detail above the chunks' own levels
// (stages/chunk_lod.h). A chunk's levels keep its border locked so that it
// meets its neighbours at any level without cracks; past a few hundred
// triangles that border is most of what is left, and a far field of thousands
// of chunks stays at hundreds of thousands of triangles however far away.
// Merging a kd-subtree's chunks welds their shared borders, so the group
// simplifies across them while its own border (where it meets the rest of the
// model) stays locked: the hierarchical LOD of Erikson, Manocha & Baxter 2001
// ("HLODs for faster display of large static and dynamic environments", I3D)
// with the locked-border clusters of Karis et al. 2021 ("Nanite"). Chunk ids
// follow the kd-tree's leaf order (stages/chunking.h), so a group is a run of
// consecutive ids.
#pragma once

#include <cstdint>
#include <span>

#include "stages/geometry.h"

namespace cellbake {

// One chunk holding every triangle of `members` (in order, each keeping its
// colour, uv, normal and material), with id `id`, origin the centre of the
// merged bounds. World positions are snapped to a grid of `weld` metres
// around that origin before they become floats, so the copies two members
// hold of a shared border vertex (each stored relative to its own origin)
// land on one position, and vertices equal in every attribute are welded:
// the members' shared borders become interior edges. Where members differ
// in attributes (uvs or normals on some only) the merged chunk has them on
// all: uv (0, 0); for normals, the corners of a member without them carry
// their triangle's face normal (triangles of one plane still share them).
// Throws std::invalid_argument for
// no members, a null member, `weld` not finite and > 0, or a member index
// out of range.
Chunk merge_chunks(std::span<const Chunk* const> members, std::int64_t id, double weld = 1e-6);

}  // namespace cellbake
