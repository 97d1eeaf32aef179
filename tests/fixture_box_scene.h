// Analytic cube-map samples of scenes made of axis-aligned boxes: exact
// planar depths by ray casting, one flat colour per box. For stage tests that
// need samples with known answers without a GL context.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "stages/cube_map.h"

namespace cellbake::test {

struct SceneBox {
  Box3d box;
  Rgba8 color{200, 200, 200, 255};
};

// Distance t along direction d (not normalised) from o to the box, or +inf.
inline double ray_box(const Vec3d& o, const Vec3d& d, const Box3d& b) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1 && t0 > 0 ? t0 : std::numeric_limits<double>::infinity();
}

// The cube sample at `eye` of `scene`, `size` pixels per face edge (pixel-centre rays).
inline CubeSample box_scene_sample(const Vec3d& eye, const std::vector<SceneBox>& scene, int size) {
  CubeSample s;
  s.eye = eye;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis b = cube_face_basis(f);
    CubeFace& face = s.faces[static_cast<std::size_t>(f)];
    face.size = size;
    face.color.assign(std::size_t(size) * size, Rgba8{0, 0, 0, 0});
    face.depth.assign(std::size_t(size) * size, kBackgroundDepth);
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) {
        const Vec3d d = cube_face_direction(b, 2 * (i + 0.5) / size - 1, 1 - 2 * (j + 0.5) / size);
        double best = std::numeric_limits<double>::infinity();
        Rgba8 c{0, 0, 0, 0};
        for (const SceneBox& sb : scene) {
          const double t = ray_box(eye, d, sb.box);
          if (t < best) best = t, c = sb.color;
        }
        if (std::isfinite(best)) {
          face.depth[std::size_t(j) * size + i] = static_cast<float>(best);  // forward component of d is 1
          face.color[std::size_t(j) * size + i] = c;
        }
      }
  }
  return s;
}

}  // namespace cellbake::test
