// Floor finder: the walkable floor heights of a model, for `cellbake info`'s
// suggested bake. Rays are cast straight down through the model on a regular
// grid over its horizontal extent; every upward-facing surface a ray passes
// (normal within ~45 degrees of up) is a hit. A histogram of hit heights,
// counting each grid ray at most once per bin, has a peak at each floor; a hit
// counts only with headroom (no surface of any orientation less than
// `min_headroom` above it on the same ray), so table tops and the insides of
// slabs do not make floors. Exact CPU ray/triangle tests over every chunk: the
// rays are vertical, so each triangle is rasterised onto the grid in the
// horizontal plane (no acceleration structure needed). Floors under a roof
// come first when peaks compete. Deterministic.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

struct FloorFinderParams {
  int up_axis = 2;  // 2: z up, 1: y up (the other two axes are horizontal)
  int grid = 96;    // rays along the longer horizontal side; the shorter gets proportionally fewer (≥ 2)
  double bin_size = 0.05;       // histogram bin height, model units
  double min_up_cos = 0.7;      // a surface faces up when its unit normal · up ≥ this
  double min_headroom = 1.9;    // model units of free space a floor needs above it (eye height 1.7 + margin)
  double min_fraction = 0.05;   // a floor: a peak hit by at least this fraction of the rays that hit anything
  double min_separation = 1.0;  // floors closer than this (model units) are one floor: the stronger peak wins
};

struct Floor {
  double height = 0;               // along the up axis, model units (the peak bin's mean hit height)
  std::uint64_t rays = 0;          // grid rays that hit this floor (within ± min_separation / 2)
  std::uint64_t covered_rays = 0;  // of those, rays with some surface above the floor (indoors)
  Box3d extent;                    // the hit points' box (the up axis' range is the floor's height)
  Box3d covered_extent;            // the covered hit points' box (empty when none is covered)
};

// Where people walk on `floor`: its covered extent (hit points with something
// above them: indoors), or, with nothing covered (a roof, open ground), all of
// its extent. `cellbake info`'s suggested region and a `--floors` bake without
// regions both use it.
inline const Box3d& walkable_extent(const Floor& floor) {
  return floor.covered_extent.empty() ? floor.extent : floor.covered_extent;
}

struct FloorFinderResult {
  std::vector<Floor> floors;   // ascending height; empty when no ray hit an upward-facing surface
  std::uint64_t rays = 0;      // grid rays cast
  std::uint64_t rays_hit = 0;  // rays that hit any surface
  double ray_spacing = 0;      // grid step, model units
};

// Finds the floors of everything `source` holds. Reads every chunk once (an
// empty model gives no floors). Throws what ChunkSource::load throws.
FloorFinderResult find_floors(const ChunkSource& source, const FloorFinderParams& params = {});

}  // namespace cellbake
