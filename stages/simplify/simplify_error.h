// The error of a simplified face mesh measured against the dense pixel-grid
// mesh it came from, in the face's own screen space (pixels) and in relative
// depth along the eye rays. Works for any simplified mesh whose vertices carry
// the face uv (ours, meshoptimizer's, OpenMesh's), so the benchmarks compare
// methods with one ruler.
#pragma once

#include <cstddef>

#include "stages/cube_map.h"
#include "stages/simplify/simplify_grid.h"
#include "stages/simplify/simplify_outline.h"

namespace cellbake {

struct SimplifyError {
  // Max over the dense mesh's vertices of |z_out - z_in| / z_in, where z_out is
  // the planar depth of the simplified surface on the same eye ray (taken from
  // the simplified triangles that hold the vertex and cover a coverage sample
  // of a pixel next to it). Vertices on
  // an outline (a silhouette, skin or coverage edge inside the face) are left
  // out, and so are pixels a triangle of another surface region covers: an
  // outline may move (max_boundary_error_px), so the surface on its other
  // side may legitimately cover them (a triangle is of a region when those
  // of its vertices that copy a dense vertex of a single region all name it).
  double max_depth_error_relative = 0;
  // Screen-space Hausdorff distance, in pixels, between the dense mesh's
  // outlines and the simplified mesh's boundary edges (edges of one triangle)
  // off the face square's sides, both ways: how far silhouettes, skins and
  // coverage edges moved. Sampled every 1/8 px along the edges, so it is at
  // most 1/16 px below the exact distance; saturates at 64 px.
  double max_boundary_error_px = 0;
  // Screen coverage, sampled at 4 points per pixel (0.0313 / 0.0711 px inside each
  // pixel corner): samples the dense mesh covers and the simplified one does not,
  // and samples the simplified mesh covers where the dense one has no surface.
  // Both 0 means silhouettes and borders did not move by more than ~0.07 px;
  // straightened outlines (up to max_boundary_error_px) make both non-zero.
  std::size_t uncovered_samples = 0;
  std::size_t spurious_samples = 0;
  // Simplified triangles that are degenerate or wound against the dense mesh in screen space.
  std::size_t flipped_triangles = 0;
  // Samples covered by more than one simplified triangle (overlaps, folds).
  std::size_t overlapping_samples = 0;
};

// Measures `simplified` against `dense` (a pixel grid from build_depth_meshes).
// Deterministic; O(pixels + covered area of the simplified triangles). Throws
// std::invalid_argument when `dense` is not a pixel-grid mesh.
SimplifyError measure_simplification_error(const FaceMesh& dense, const FaceMesh& simplified, int face_size);

// The same measurement from the dense mesh's grid, regions and traced (not
// straightened) outlines, as simplify_face_mesh already holds them.
SimplifyError measure_simplification_error(const FaceMesh& dense, const FaceGrid& grid, const FaceRegions& regions,
                                           const FaceOutlines& outlines, const FaceMesh& simplified);

}  // namespace cellbake
