// The GL sampling backend's panorama (Wilson 2002, ch. 3 and §7.3.1.3):
// the cube map of a sample point drawn by a ChunkRenderer, with the
// backend-neutral conventions of stages/sample/sample.h.
#pragma once

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/geometry.h"
#include "stages/render/chunk_renderer.h"
#include "stages/sample/sample.h"

namespace cellbake {

// Renders the cube map at `eye` of everything outside `cull_box` (fragments
// strictly inside it are discarded, so off-centre eyes work). Chunks are drawn
// per face nearest first (by the nearest forward distance of their bounds, ties
// by id) through ChunkRenderer::draw_unoccluded(), which skips chunks provably
// hidden behind those already drawn; a chunk is loaded from `source` only when
// some face's frustum needs it, it is not hidden there, and `renderer` has not
// cached it. Each face's `seen` lists the triangles that drew its pixels
// (ChunkRenderer's primitive ids, turned into SeenChunks by
// stages/far/seen_triangles.h as the ray-casting backend's hits are). Throws
// std::invalid_argument for bad parameters and passes on load and GL errors.
// Deterministic for the same inputs, renderer settings and Mesa version.
CubeSample sample_cube(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                       const ChunkSource& source, ChunkRenderer& renderer);

}  // namespace cellbake
