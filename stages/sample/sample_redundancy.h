// Redundant-point removal for delta scans (Wilson 2002, §5.2.1 and Appendix A):
// a pixel of a delta sample whose surface point an ancestor sample already
// holds is removed (made background) before meshing, so each delta scan keeps
// only what its ancestors did not see.
#pragma once

#include <cstddef>
#include <span>

#include "stages/cube_map.h"

namespace cellbake {

struct RedundancyParams {
  // A point counts as held by an ancestor when its inverse depth agrees with
  // the ancestor's surface, interpolated at the point's projection, within
  // `tolerance` (relative) plus the interpolation error estimated from the
  // ancestor's local curvature. On planes the interpolation is exact, so this
  // only has to cover float32 depth rounding: two parallel surfaces 1e-4 of
  // their distance apart are still told apart.
  double tolerance = 5e-5;
  // Where the ancestor's 2x2 neighbourhood spans a depth jump larger than this
  // (relative), it is not interpolated; the point then matches one of the four
  // pixels' own surfaces, extrapolated linearly from that pixel and its
  // same-surface neighbour towards the point, within `tolerance` plus
  // `edge_tolerance` times the extrapolated change; along an axis without
  // such a neighbour (a feature one pixel thin, or the last pixel before a
  // silhouette) the surface is unknown and `unknown_slope` (relative depth per
  // pixel of offset; 0.02 is a surface at ~80 degrees incidence at 512^2) is
  // allowed instead. The pixel quad an ancestor's depth mesh draws reaches
  // half a pixel past its centre, so this is what that mesh shows there.
  double jump = 0.1;
  double edge_tolerance = 0.25;
  double unknown_slope = 0.02;
  // Kept specks of fewer pixels than this (8-connected, not touching the
  // background) are removed too: a delta mesh for them costs more than the
  // pixel of parallax it would fix.
  int min_island = 4;
  // Kept pixels grow by this many pixels (8-neighbourhood) back into the
  // removed ones, so that a delta mesh overlaps its ancestors' meshes along
  // the seam instead of leaving a crack there (the depth test resolves it).
  int keep_margin = 2;
};

struct RedundancyStats {
  std::size_t covered = 0;  // non-background pixels of the delta sample before removal
  std::size_t removed = 0;  // of those, removed as redundant
};

// Removes from `delta` (in place: depth = background, colour = 0) every pixel
// whose surface point one of `ancestors` already holds, then restores removed
// pixels within keep_margin of a kept one. Ancestors must be other samples of
// the same scene with faces of the same size. Deterministic. Throws
// std::invalid_argument for face size mismatches or bad parameters.
RedundancyStats remove_redundant_pixels(CubeSample& delta, std::span<const CubeSample* const> ancestors,
                                        const RedundancyParams& params = {});

// Whether `ancestor` holds the world point `point` (same rule as above).
bool sample_holds_point(const CubeSample& ancestor, const Vec3d& point, const RedundancyParams& params = {});

}  // namespace cellbake
