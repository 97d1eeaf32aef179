// Ray casting of analytic boxes and cylinders (slab test; quadratic for the
// cylinder side). See depth_mesh_analytic_scene.h.
#include "pipeline/scenes/depth_mesh_analytic_scene.h"

#include <cmath>
#include <cstdint>
#include <limits>

namespace cellbake {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Smallest positive ray parameter t (point = eye + t dir) on the box surface.
double hit_box(const Box3d& b, Vec3d eye, Vec3d dir) {
  double t_near = -kInf, t_far = kInf;
  for (int k = 0; k < 3; ++k) {
    if (dir[k] == 0) {
      if (eye[k] < b.lo[k] || eye[k] > b.hi[k]) return kInf;
      continue;
    }
    double t0 = (b.lo[k] - eye[k]) / dir[k], t1 = (b.hi[k] - eye[k]) / dir[k];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
  }
  if (t_near > t_far) return kInf;
  if (t_near > 0) return t_near;
  if (t_far > 0) return t_far;
  return kInf;
}

double hit_cylinder(const AnalyticCylinder& c, Vec3d eye, Vec3d dir) {
  const double ox = eye.x - c.cx, oy = eye.y - c.cy;
  const double a = dir.x * dir.x + dir.y * dir.y;
  if (a == 0) return kInf;
  const double b = 2 * (ox * dir.x + oy * dir.y);
  const double cc = ox * ox + oy * oy - c.radius * c.radius;
  const double disc = b * b - 4 * a * cc;
  if (disc < 0) return kInf;
  const double sq = std::sqrt(disc);
  for (double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
    if (t <= 0) continue;
    const double z = eye.z + t * dir.z;
    if (z >= c.z0 && z <= c.z1) return t;
  }
  return kInf;
}

}  // namespace

CubeSample raycast_analytic_scene(const AnalyticScene& scene, Vec3d eye, int face_size) {
  CubeSample sample;
  sample.eye = eye;
  const int n = face_size;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis basis = cube_face_basis(f);
    CubeFace& face = sample.faces[f];
    face.size = n;
    face.depth.assign(std::size_t(n) * n, kBackgroundDepth);
    face.color.assign(std::size_t(n) * n, Rgba8{0, 0, 0, 0});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double s = 2.0 * (i + 0.5) / n - 1.0, t = 1.0 - 2.0 * (j + 0.5) / n;
        const Vec3d dir = cube_face_direction(basis, s, t);  // forward component 1: t is planar depth
        double best = kInf;
        std::uint8_t shade = 0;
        for (std::size_t k = 0; k < scene.boxes.size(); ++k) {
          const double h = hit_box(scene.boxes[k], eye, dir);
          if (h < best) best = h, shade = std::uint8_t(60 + 37 * k % 190);
        }
        for (std::size_t k = 0; k < scene.cylinders.size(); ++k) {
          const double h = hit_cylinder(scene.cylinders[k], eye, dir);
          if (h < best) best = h, shade = std::uint8_t(80 + 53 * k % 170);
        }
        if (best < kInf) {
          face.depth[std::size_t(j) * n + i] = float(best);
          face.color[std::size_t(j) * n + i] = {shade, shade, shade, 255};
        }
      }
  }
  return sample;
}

}  // namespace cellbake
