// Analytic scenes ray-cast into a cube-map sample, without GL: axis-aligned
// boxes (seen from outside, or from inside when the eye is in them) and
// vertical cylinders. A synthetic input source for depth-mesh and
// simplification tests and benchmarks, with exactly known depths.
#pragma once

#include <vector>

#include "stages/cube_map.h"

namespace cellbake {

struct AnalyticCylinder {
  double cx = 0, cy = 0, radius = 1;  // axis parallel to z through (cx, cy)
  double z0 = -1, z1 = 1;             // height range (open ends: no caps)
};

struct AnalyticScene {
  std::vector<Box3d> boxes;
  std::vector<AnalyticCylinder> cylinders;
};

// Ray-casts every pixel centre of a face_size^2 cube map from `eye`: depth is the
// planar view depth of the nearest hit (cube_map.h convention), +inf where
// nothing is hit; colour is a flat grey per primitive. Deterministic.
CubeSample raycast_analytic_scene(const AnalyticScene& scene, Vec3d eye, int face_size);

}  // namespace cellbake
