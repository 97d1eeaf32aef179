// Panoramic colour + depth sampling of a view cell's far field (Wilson 2002,
// ch. 3 and §7.3.1.3): from a sample point, render only the geometry outside
// the cell's cull box into the six 90-degree faces of a cube map (conventions
// in stages/cube_map.h), loading only the chunks some face can see.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/geometry.h"

namespace cellbake {

struct SampleParams {
  int face_size = 512;       // pixels per face edge of the result
  // Each face is rendered at face_size * supersample pixels per edge and box-
  // filtered down over supersample x supersample blocks (the thesis rendered
  // 1024^2 and kept 512^2). Per output pixel, over the block's covered
  // subpixels (those with finite depth):
  //  * colour is their average (background (0, 0, 0, 0) when none is covered);
  //  * depth is the harmonic mean 1 / mean(1 / d) when every subpixel is
  //    covered and their depths agree within `depth_agreement` (max <= min *
  //    (1 + depth_agreement)): 1/d is affine in screen space on a plane and the
  //    subpixel centres are symmetric about the pixel centre, so this is the
  //    exact depth at the pixel centre of a planar surface; otherwise the
  //    nearest (minimum) depth, because any blend of two surfaces' depths
  //    would put a point where no surface is. A pixel with any covered
  //    subpixel counts as covered, so thin far-away features are kept.
  int supersample = 1;
  double depth_agreement = 0.05;
  double near_plane = 0.01;  // metres along each face's forward axis; nearer geometry is clipped
  // False for samples whose colours nobody reads (visibility samples: only
  // their depths and seen triangles count): a backend may leave the colour
  // transparent black (the Embree backend does; the GL one draws it anyway).
  bool colour = true;
};

// Throws std::invalid_argument unless `eye` is finite and `params` are valid
// (face_size, supersample >= 1 with face_size * supersample <= 16384, a
// positive finite near plane, depth_agreement >= 0). Every sampling backend
// checks its inputs with it.
void validate_sample_inputs(const Vec3d& eye, const SampleParams& params);

// The chunks that can contribute to cube face `face` (0..5) seen from `eye`:
// those returned by source.query() for the box around the face's frustum out
// to the model bounds, whose bounds then meet the frustum (four side planes
// and the near plane) and do not lie strictly inside `cull_box`. Sorted by id.
// Loads nothing.
std::vector<ChunkRef> chunks_in_face(int face, const Vec3d& eye, const Box3d& cull_box, double near_plane,
                                     const ChunkSource& source);

// chunks_in_face() ordered nearest first: by the nearest forward distance
// of their bounds from `eye` along the face's axis, ties by id.
std::vector<ChunkRef> chunks_in_face_nearest_first(int face, const Vec3d& eye, const Box3d& cull_box,
                                                   double near_plane, const ChunkSource& source);

// The stored face of a (face_size * supersample)^2 rendering: the pixels as
// they are (moved out of `color` and `depth`, which are left empty) or
// downsample_face()'d. Shared by every sampling backend.
CubeFace finish_face(std::vector<Rgba8>& color, std::vector<float>& depth, const SampleParams& params);

// Box-filters a (size * factor)^2 rendering down to size^2 as SampleParams
// describes (row-major, row 0 at the top). Exposed for tests.
CubeFace downsample_face(const std::vector<Rgba8>& color, const std::vector<float>& depth, int size, int factor,
                         double depth_agreement);

}  // namespace cellbake
