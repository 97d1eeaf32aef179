// Simplified levels of a chunk for the far field's level-of-detail tier
// (issue #35). Each level simplifies the chunk itself (not the level before)
// by edge collapse under quadric error metrics (Garland & Heckbert 1997, as
// meshoptimizer's meshopt_simplify implements it) to about half the triangles
// of the level before, first with the chunk's border vertices locked
// (meshopt_SimplifyLockBorder): a chunk at such a level meets its neighbours
// at any locked level, and the exact triangles of the near field, without
// cracks (the locked-border clusters of Karis et al. 2021, "Nanite", with the
// store's chunks as clusters). Where the lock leaves nothing to collapse
// (pipes cut by chunk borders: half the edges of a plant's coarsest locked
// levels are open borders), further levels are made without it: border
// vertices then collapse along their borders, so a gap may open between
// neighbours, as wide as both sides' error; such a level records a multiple
// of its error (unlocked_error_scale), so a pixel budget on the error bounds
// the gaps too. A far chunk is
// drawn at the coarsest level whose error,
// seen from the nearest point a view may stand, stays under a pixel budget
// (the screen-space error test of Luebke et al. 2003, "Level of Detail for 3D
// Graphics", ch. 4); which tiles draw geometry at all is the far choice's
// measure of triangles (stages/far/far_choice.h, after Maciel & Shirley 1995).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

struct ChunkLodParams {
  int max_levels = 8;                // levels 1 .. max_levels at most
  double ratio = 0.5;                // each level aims at this fraction of the level before's triangles
  std::size_t min_triangles = 64;    // no level is made from fewer triangles than this
  double min_reduction = 0.85;       // a level must keep at most this fraction of the level before's, else the
                                     // locked levels end (locked borders and seams leave nothing more to collapse)
  bool unlocked_levels = true;       // then go on without the border lock, till that too stops reducing
  double unlocked_error_scale = 8;   // such a level records meshoptimizer's error times this: 2 for the gap to a
                                     // neighbour whose border moved the other way, and 4 for thin parts cut by the
                                     // border, whose cross-sections collapse and change whole pixels. Measured on
                                     // the 12.7 M plant's cells 28-36 at the bake's 1 px: 2 costs 4.7 dB for 43 %
                                     // fewer far triangles, 8 nothing for 15 % (docs/benchmarks.md, L1)
};

struct ChunkLod {
  ChunkLodRef ref;  // level, error (metres) and triangle count
  Chunk chunk;      // the level: same id, origin and bounds as the chunk, only the vertices it uses
};

// The levels of `chunk` (level 1, 2, ...; possibly none), each with the
// largest distance meshoptimizer bounds between it and the chunk (in the
// chunk's units, metres; times params.unlocked_error_scale for a level made
// without the border lock), errors never decreasing from level to level. Vertices keep their attributes (colour, texture
// coordinates, normal); a vertex shared by triangles of different materials
// is split first, so material borders stay where they are and every
// triangle keeps its material. Deterministic. A chunk with a non-finite
// position, or with fewer than 2 * params.min_triangles triangles, has no levels.
std::vector<ChunkLod> build_chunk_lods(const Chunk& chunk, const ChunkLodParams& params = {});

// The shortest distance between a point of `a` and a point of `b` (0 when
// they overlap or touch).
double box_distance(const Box3d& a, const Box3d& b);

// The largest error a far chunk may have: `error_px` pixels of a cube face
// `face_size` pixels wide (90 degrees), seen from `distance` metres (the
// nearest a view may come to the chunk).
double allowed_lod_error(double distance, double error_px, int face_size);

// The coarsest of `levels` whose error is at most `allowed_error` (0: none is;
// draw the chunk itself). `levels` ascend by level, errors growing.
int choose_lod_level(std::span<const ChunkLodRef> levels, double allowed_error);

// The median over `chunk`'s triangles of their width: twice the area over
// the longest edge, the height across it (how thin a triangle is, in the
// chunk's units). Triangles with a non-finite or coincident corner, or no
// area, are skipped; 0 when none is left.
double median_triangle_width(const Chunk& chunk);

// Whether the triangles a sample saw of a chunk may miss what other eyes of
// the cell see of it: its triangles (of median width `width`) are narrower
// than `width_px` pixels of a cube face `face_size` pixels wide seen from
// `distance` metres, so rays through pixel centres skip some of them (thin
// pipes, rails). Such a chunk is better drawn whole at a simplified level
// than as the subset the samples hit.
bool seen_subset_may_miss(double width, double distance, double width_px, int face_size);

}  // namespace cellbake
