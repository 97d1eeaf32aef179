// A frame's chunks coarsened to fit a triangle budget (issue #38: smooth
// frames on a software rasteriser where a cell draws hundreds of thousands of
// triangles). What a cell draws in view — near-field chunks, seen subsets of
// far chunks, store levels of far chunks, whole far chunks — may be drawn at a
// coarser simplified level of its store chunk (stages/chunk_lod.h), chosen as
// a screen-space-error cut through the levels (stages/far/lod_cut.h, after
// Luebke et al. 2003, "Level of Detail for 3D Graphics", ch. 4): the smallest
// error in pixels at which everything fits, so what is near the eye keeps its
// triangles longest. Pure: no GL.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

struct ChunkDrawItem {
  std::int64_t chunk_id = 0;    // the store's chunk it comes from
  int level = 0;                // what the cell draws: 0 the chunk's own triangles (all or a subset), >= 1 a store level
  std::uint32_t triangles = 0;  // its triangles as the cell draws it
  Box3d bounds;                 // world bounds
};

// Per item, the level to draw it at: its own, or a coarser store level of its
// chunk (a level above its own with fewer triangles than it): the cut at the
// smallest pixel error whose triangles are at most `max_triangles` — or, when
// even the coarsest levels draw more, the coarsest. An item's pixel size is
// `metres_per_pixel_per_metre` times the distance from `eye` to its bounds; an
// item around the eye keeps its level. max_triangles 0: every item's own level.
std::vector<int> levels_for_triangle_budget(std::span<const ChunkDrawItem> items, const ChunkSource& source,
                                            const Vec3d& eye, double metres_per_pixel_per_metre,
                                            std::uint64_t max_triangles);

}  // namespace cellbake
