// Slab test for the open box interval: Kay & Kajiya 1986, "Ray tracing complex
// scenes", SIGGRAPH.
#include "stages/raycast/ray_segments.h"

namespace cellbake {

EyeBox eye_relative_box(const Box3d& box, const Vec3d& eye) {
  EyeBox b;
  if (box.empty()) return b;
  for (int k = 0; k < 3; ++k)
    if (!(box.lo[k] < box.hi[k])) return b;
  b.lo = box.lo - eye;
  b.hi = box.hi - eye;
  b.none = false;
  return b;
}

}  // namespace cellbake
