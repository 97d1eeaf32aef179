// One far geometry row of a cell checked against the stored chunk it names
// (issue #37, item 3): check_cell's store-aware part, pure, so the fuzz target
// fuzz_far_geometry can drive it with arbitrary rows.
#pragma once

#include <span>
#include <string>

#include "stages/chunk_source.h"
#include "stages/geometry.h"
#include "storage/cell_db.h"

namespace cellbake {

// "" when `row`'s level is sound on its own (issue #35), else what is wrong:
// a level is 0..kMaxFarGeometryLevel, and a row of level >= 1 is whole with
// an empty geometry blob. Never throws.
std::string far_geometry_level_problem(const FarGeometryRow& row);

// "" when `row` is sound against `stored` (the store's chunk `row.chunk_id`)
// and `lods` (the store's levels of that chunk, ChunkSource::lods; read only
// for a row of level >= 1), else what is wrong: a whole row must have the
// chunk's triangle count and bounds; a level row (far_geometry_level_problem)
// the chunk's bounds and a level `lods` lists with exactly the row's triangle
// count; a triangle-list row's numbers must decode and lie within the chunk,
// number row.triangles, and its bounds and origin be those of the triangles
// named (chunk_subset). Rows holding a chunk blob of their own (baked before
// far_choice version 3) pass here. Never throws.
std::string far_geometry_problem(const FarGeometryRow& row, const Chunk& stored,
                                 std::span<const ChunkLodRef> lods = {});

}  // namespace cellbake
