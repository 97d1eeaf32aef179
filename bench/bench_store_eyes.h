// Eye positions for benchmarks that run on a real geometry store (named by the
// CELLBAKE_BENCH_STORE environment variable): CELLBAKE_BENCH_EYES
// ("x,y,z;x,y,z;...") when set, else 8 points along the x midline of the
// model's bounds at a quarter of its z extent. Header-only.
#pragma once

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

inline std::vector<Vec3d> bench_eyes(const Box3d& model) {
  std::vector<Vec3d> eyes;
  if (const char* text = std::getenv("CELLBAKE_BENCH_EYES")) {
    std::stringstream points(text);
    std::string point;
    while (std::getline(points, point, ';')) {
      Vec3d e;
      char comma = 0;
      std::stringstream(point) >> e.x >> comma >> e.y >> comma >> e.z;
      eyes.push_back(e);
    }
    return eyes;
  }
  for (int i = 0; i < 8; ++i)
    eyes.push_back({model.lo.x + (model.hi.x - model.lo.x) * (i + 0.5) / 8, model.center().y,
                    model.lo.z + 0.25 * (model.hi.z - model.lo.z)});
  return eyes;
}

}  // namespace cellbake
