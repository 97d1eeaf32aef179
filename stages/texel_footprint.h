// Which texels of a face image a textured depth mesh can read: the viewer
// draws each face mesh with its image bilinearly filtered without mipmaps
// (viewer/tdm_renderer.cpp), so a point at image position (x, y) (pixels,
// texel centres at i + 0.5) reads the 2 x 2 texels around it, and texel i is
// read exactly when some point of some triangle lies within one pixel of its
// centre on both axes. Texels no triangle reads (pixels of tiles drawn as
// exact geometry, pixels a delta scan removed, outlines straightened inward)
// can take any colour: filled smoothly they cost the image codec little.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/cube_map.h"

namespace cellbake {

// 1 for each texel (row-major, row 0 at v = 0) of a size x size image that
// `mesh` reads through its texture coordinates (u, v in [0, 1] across the
// image), 0 for the others. Exact up to float rounding, which it errs on the
// side of reading. Throws std::invalid_argument for size < 1 or an index out
// of range.
std::vector<std::uint8_t> texels_read_by(const FaceMesh& mesh, int size);

}  // namespace cellbake
