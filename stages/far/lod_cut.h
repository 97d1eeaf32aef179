// A view-dependent cut through the store's chunk levels: the yardstick the
// far field is measured against (issue #35). Each chunk in view is drawn at
// the coarsest of its simplified levels (stages/chunk_lod.h: locked-border
// levels of the store's chunks, the clusters of a Nanite-style hierarchy,
// Karis et al. 2021) whose error, projected at the chunk's nearest point,
// stays under a pixel threshold (the screen-space error test of Luebke et
// al. 2003, "Level of Detail for 3D Graphics", ch. 4). Either the threshold
// is given, or the smallest threshold whose cut fits a triangle count is
// searched: what such a cut draws with the triangles the cell drew.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "stages/chunk_source.h"

namespace cellbake {

struct LodCutChunk {
  // Metres one pixel spans at the chunk's nearest point from the eye; 0 when
  // the eye is inside the chunk's bounds (it is then always drawn exactly).
  double pixel_size = 0;
  std::uint32_t triangles = 0;      // the chunk's own triangles (level 0)
  std::vector<ChunkLodRef> levels;  // its simplified levels, ascending by level
};

struct LodCut {
  std::vector<int> levels;     // per chunk, in input order: 0 exact, else the level drawn
  double error_px = 0;         // the threshold the cut was made at
  std::uint64_t triangles = 0; // what it draws
};

// Each chunk at its coarsest level whose error is at most `error_px` times
// its pixel size. Deterministic; the triangle count never grows with error_px.
LodCut lod_cut_at_error(std::span<const LodCutChunk> chunks, double error_px);

// The cut at the smallest threshold (among those where some chunk changes
// level) whose triangles are at most `max_triangles`; when even the coarsest
// cut draws more, the coarsest cut (at the largest such threshold).
LodCut lod_cut_for_triangles(std::span<const LodCutChunk> chunks, std::uint64_t max_triangles);

}  // namespace cellbake
