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

void FaceSlabs::set(const FaceBasis& b, const EyeBox& box, std::span<const double> coordinate,
                    std::span<const double> inverse_coordinate) {
  columns_.assign(coordinate.size(), SlabInterval{});
  rows_.assign(coordinate.size(), SlabInterval{});
  if (box.none) {
    forward_ = SlabInterval::never();
    return;
  }
  const auto axis_of = [](const Vec3d& v) { return v.x != 0 ? 0 : v.y != 0 ? 1 : 2; };
  const int forward = axis_of(b.forward), right = axis_of(b.right), up = axis_of(b.up);
  const double f = b.forward[forward], r = b.right[right], u = b.up[up];
  forward_ = slab_interval(f, f, box.lo[forward], box.hi[forward]);
  for (std::size_t i = 0; i < coordinate.size(); ++i) {
    const double s = coordinate[i], inverse_s = inverse_coordinate[i];
    columns_[i] = slab_interval(r * s, r * inverse_s, box.lo[right], box.hi[right]);
    rows_[i] = slab_interval(u * -s, u * -inverse_s, box.lo[up], box.hi[up]);
  }
}

}  // namespace cellbake
