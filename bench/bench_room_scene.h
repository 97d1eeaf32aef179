// The analytic room the simplify and depth-mesh benchmarks share: a closed box
// of side 60 seen from near its centre, with boxes and pipes at several depths
// (no background). Header-only.
#pragma once

#include "pipeline/scenes/depth_mesh_analytic_scene.h"

namespace cellbake {

// Ray-cast cube map of the room at face_size^2 per face.
inline CubeSample bench_room_sample(int face_size) {
  AnalyticScene scene;
  scene.boxes.push_back(Box3d::cube({0, 0, 0}, 30.0));
  scene.boxes.push_back({{4, -3, -6}, {6, 2, 1}});
  scene.boxes.push_back({{12, 3, -30}, {14, 9, 4}});
  scene.boxes.push_back({{20, -12, -8}, {24, -4, 12}});
  for (int k = 0; k < 6; ++k) scene.cylinders.push_back({7.0 + 3 * k, -8.0 + 3.1 * k, 0.08 + 0.05 * k, -30, 30});
  scene.cylinders.push_back({9, 5, 1.5, -30, 2});
  return raycast_analytic_scene(scene, {0.2, 0.1, 0.3}, face_size);
}

}  // namespace cellbake
