// Analytic depth cube maps for tests: axis-aligned boxes ray-cast exactly at
// every pixel centre (stages/cube_map.h conventions). Boxes are surfaces, not
// solids: an eye inside a box sees its inner walls (a room), an eye outside
// sees its outer faces (a pillar). No GL, no geometry store.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "stages/cube_map.h"
#include "stages/geometry.h"

namespace cellbake::test {

// Nearest positive ray parameter u at which eye + u * dir meets the surface of
// `box`, or +inf. With dir's forward component 1, u is the planar depth.
inline double ray_box_surface(const Vec3d& eye, const Vec3d& dir, const Box3d& box) {
  double near = -std::numeric_limits<double>::infinity(), far = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0) {
      if (eye[a] < box.lo[a] || eye[a] > box.hi[a]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double t0 = (box.lo[a] - eye[a]) / dir[a], t1 = (box.hi[a] - eye[a]) / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    near = std::max(near, t0);
    far = std::min(far, t1);
  }
  if (near > far) return std::numeric_limits<double>::infinity();
  if (near > 0) return near;
  if (far > 0) return far;
  return std::numeric_limits<double>::infinity();
}

// Nearest hit over all boxes, +inf for none.
inline double ray_boxes(const Vec3d& eye, const Vec3d& dir, const std::vector<Box3d>& boxes) {
  double best = std::numeric_limits<double>::infinity();
  for (const Box3d& b : boxes) best = std::min(best, ray_box_surface(eye, dir, b));
  return best;
}

// A cube sample at `eye` of `boxes`, size x size per face, depth only (colours
// stay default): planar depth of the nearest box surface through each pixel
// centre, kBackgroundDepth where none.
inline CubeSample analytic_cube_sample(const Vec3d& eye, const std::vector<Box3d>& boxes, int size) {
  CubeSample sample;
  sample.eye = eye;
  for (int f = 0; f < kCubeFaces; ++f) {
    CubeFace& face = sample.faces[f];
    face.size = size;
    face.color.assign(static_cast<std::size_t>(size) * size, Rgba8{});
    face.depth.assign(static_cast<std::size_t>(size) * size, kBackgroundDepth);
    const FaceBasis basis = cube_face_basis(f);
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) {
        const double s = 2 * (i + 0.5) / size - 1, t = 1 - 2 * (j + 0.5) / size;
        const double d = ray_boxes(eye, cube_face_direction(basis, s, t), boxes);
        if (d < std::numeric_limits<double>::infinity())
          face.depth[static_cast<std::size_t>(j) * size + i] = static_cast<float>(d);
      }
  }
  return sample;
}

// A box with a flat colour, for samples that need colours too.
struct ColoredBox {
  Box3d box;
  Rgba8 color{200, 200, 200, 255};
};

// As above, with each pixel coloured by the nearest box (background (0, 0, 0, 0)).
inline CubeSample analytic_colored_cube_sample(const Vec3d& eye, const std::vector<ColoredBox>& boxes, int size) {
  std::vector<Box3d> plain;
  for (const ColoredBox& b : boxes) plain.push_back(b.box);
  CubeSample sample = analytic_cube_sample(eye, plain, size);
  for (int f = 0; f < kCubeFaces; ++f) {
    CubeFace& face = sample.faces[f];
    const FaceBasis basis = cube_face_basis(f);
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * size + i;
        face.color[k] = Rgba8{0, 0, 0, 0};
        if (!std::isfinite(face.depth[k])) continue;
        const Vec3d dir = cube_face_direction(basis, 2 * (i + 0.5) / size - 1, 1 - 2 * (j + 0.5) / size);
        double best = std::numeric_limits<double>::infinity();
        for (const ColoredBox& b : boxes) {
          const double d = ray_box_surface(eye, dir, b.box);
          if (d < best) best = d, face.color[k] = b.color;
        }
      }
  }
  return sample;
}

}  // namespace cellbake::test
