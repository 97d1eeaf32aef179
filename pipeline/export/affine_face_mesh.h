// A textured depth mesh made drawable with plain per-vertex texture
// coordinates, as glTF viewers draw them. cellbake's viewer textures a face
// mesh projectively from its sample eye (Segal et al., "Fast shadows and
// lighting effects using texture mapping", SIGGRAPH 1992; viewer/tdm_renderer):
// each point gets the texel on the sample ray through it. A glTF viewer
// interpolates (u, v) linearly over the triangle in 3D, which differs wherever
// a triangle's corners lie at different depths from the sample eye, by up to
// L (sqrt(r) - 1) / (sqrt(r) + 1) face pixels along an edge L pixels long
// whose end depths differ by the ratio r (the largest gap between the linear
// and the projective parameter on a segment). Edges over a tolerance are
// split at the point whose projection is their texture midpoint, shared
// edges alike (no T-junctions), until every edge is within it.
#pragma once

#include <cstddef>

#include "stages/cube_map.h"

namespace cellbake {

// The largest texture error, in face pixels, of linear interpolation along an
// edge `pixel_length` face pixels long whose ends lie at planar depths `qa`
// and `qb` (> 0) from the sample eye: pixel_length (sqrt(r) - 1) / (sqrt(r) + 1),
// r = max / min depth.
double affine_uv_edge_error_px(double qa, double qb, double pixel_length);

// Puts every vertex of a face mesh of cube face `face` (0..5) back on the
// sample ray through its texture coordinates at its planar depth, undoing the
// mesh codec's per-axis quantisation (as viewer/tdm_renderer does), so that
// surfaces meeting on a silhouette share one outline. Throws
// std::invalid_argument for a face out of range or uvs not one per position.
void snap_to_sample_rays(FaceMesh& mesh, int face);

struct AffineRefinement {
  FaceMesh mesh;
  std::size_t edges_split = 0;
  double max_edge_error_px = 0;  // the largest affine_uv_edge_error_px over the result's edges
};

// `mesh` (positions relative to the sample eye, uvs into a `width` x `height`
// face image of cube face `face`) with edges split until every edge's
// affine_uv_edge_error_px is at most `tolerance_px` (> 0). Vertices behind or
// at the eye (planar depth <= 0, never made by the depth-mesh stage) leave
// their edges as they are. Throws std::invalid_argument for a bad face, size
// or tolerance, or uvs not one per position.
AffineRefinement refine_for_affine_uvs(const FaceMesh& mesh, int face, int width, int height, double tolerance_px);

}  // namespace cellbake
