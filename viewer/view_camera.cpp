#include "viewer/view_camera.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cellbake {
namespace {

Vec3d normalized(const Vec3d& v) { return v * (1.0 / length(v)); }

double max_dot(const Vec3d& n, const Vec3d& lo, const Vec3d& hi) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += n[k] * (n[k] >= 0 ? hi[k] : lo[k]);
  return s;
}

}  // namespace

Vec3d up_axis(const std::string& up) {
  if (up == "z") return {0, 0, 1};
  if (up == "y") return {0, 1, 0};
  throw std::invalid_argument("view: up axis must be \"z\" or \"y\", got \"" + up + "\"");
}

RenderCamera look_at_camera(const Vec3d& eye, const Vec3d& look, const Vec3d& world_up, double fov_y_deg, int width,
                            int height, double near_plane) {
  if (!is_finite(eye) || !is_finite(look)) throw std::invalid_argument("view: eye and look must be finite");
  if (!(fov_y_deg > 0 && fov_y_deg < 180)) throw std::invalid_argument("view: fov must be in (0, 180) degrees");
  if (width < 1 || height < 1) throw std::invalid_argument("view: image size must be at least 1x1");
  const Vec3d direction = look - eye;
  if (!(length(direction) > 0)) throw std::invalid_argument("view: eye and look point coincide");
  RenderCamera c;
  c.eye = eye;
  c.forward = normalized(direction);
  Vec3d side = cross(c.forward, world_up);
  if (length(side) < 1e-9 * length(world_up)) side = cross(c.forward, Vec3d{world_up.y, world_up.z, world_up.x});
  c.right = normalized(side);
  c.up = cross(c.right, c.forward);
  const double t = std::tan(fov_y_deg * 0.5 * std::acos(-1.0) / 180.0);
  const double aspect = static_cast<double>(width) / height;
  c.tan_top = t, c.tan_bottom = -t, c.tan_right = t * aspect, c.tan_left = -t * aspect;
  c.near_plane = near_plane;
  return c;
}

bool box_in_view(const RenderCamera& c, const Box3d& box) {
  if (box.empty()) return false;
  const Vec3d lo = box.lo - c.eye, hi = box.hi - c.eye;
  if (max_dot(c.forward, lo, hi) < c.near_plane) return false;
  // Inward normals of the side planes through the eye.
  const std::array<Vec3d, 4> sides = {c.right - c.forward * c.tan_left, c.forward * c.tan_right - c.right,
                                      c.up - c.forward * c.tan_bottom, c.forward * c.tan_top - c.up};
  for (const Vec3d& n : sides)
    if (max_dot(n, lo, hi) < 0) return false;
  return true;
}

std::vector<ChunkRef> chunk_refs_in_view(const RenderCamera& c, const ChunkSource& source) {
  const Box3d model = source.model_bounds();
  if (model.empty()) return {};
  double reach = -std::numeric_limits<double>::infinity();
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d p{corner & 1 ? model.hi.x : model.lo.x, corner & 2 ? model.hi.y : model.lo.y,
                  corner & 4 ? model.hi.z : model.lo.z};
    reach = std::max(reach, dot(p - c.eye, c.forward));
  }
  if (reach < c.near_plane) return {};
  Box3d frustum_box;
  for (double d : {c.near_plane, reach})
    for (double s : {c.tan_left, c.tan_right})
      for (double t : {c.tan_bottom, c.tan_top}) frustum_box.expand(c.eye + (c.forward + c.right * s + c.up * t) * d);
  std::vector<ChunkRef> refs;
  for (const ChunkRef& ref : source.query(frustum_box))
    if (box_in_view(c, ref.bounds)) refs.push_back(ref);
  std::sort(refs.begin(), refs.end(), [](const ChunkRef& a, const ChunkRef& b) { return a.id < b.id; });
  return refs;
}

std::vector<std::int64_t> chunks_in_view(const RenderCamera& c, const ChunkSource& source) {
  std::vector<std::int64_t> ids;
  for (const ChunkRef& ref : chunk_refs_in_view(c, source)) ids.push_back(ref.id);
  return ids;
}

}  // namespace cellbake
