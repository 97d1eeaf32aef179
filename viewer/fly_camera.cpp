#include "viewer/fly_camera.h"

#include <algorithm>
#include <cmath>

#include "viewer/view_camera.h"

namespace cellbake {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

// Horizontal axes a, b with a x b = up.
void horizontal_axes(const Vec3d& up, Vec3d& a, Vec3d& b) {
  if (std::abs(up.y) > 0.5) {
    a = {0, 0, 1}, b = {1, 0, 0};
  } else {
    a = {1, 0, 0}, b = {0, 1, 0};
  }
}

}  // namespace

Vec3d FlyCamera::forward() const {
  Vec3d a, b;
  horizontal_axes(up, a, b);
  const double yaw = yaw_deg * kDegree, pitch = pitch_deg * kDegree;
  const Vec3d horizontal = a * std::cos(yaw) + b * std::sin(yaw);
  return horizontal * std::cos(pitch) + up * std::sin(pitch);
}

void FlyCamera::move(double ahead, double right, double rise, double seconds) {
  const double step = speed * seconds;
  Vec3d f = forward();
  if (walk) {
    f = f - up * dot(f, up);
    const double l = length(f);
    if (l > 0) f = f * (1 / l);
  }
  Vec3d r = cross(f, up);
  const double lr = length(r);
  if (lr > 0) r = r * (1 / lr);
  position = position + f * (ahead * step) + r * (right * step);
  if (walk) {
    position = position + up * (floor + eye_height - dot(position, up));
  } else {
    position = position + up * (rise * step);
  }
}

void FlyCamera::turn(double yaw_delta_deg, double pitch_delta_deg) {
  yaw_deg = std::fmod(yaw_deg + yaw_delta_deg, 360.0);
  pitch_deg = std::clamp(pitch_deg + pitch_delta_deg, -89.0, 89.0);
}

RenderCamera FlyCamera::camera(double fov_y_deg, int width, int height, double near_plane) const {
  return look_at_camera(position, position + forward(), up, fov_y_deg, width, height, near_plane);
}

}  // namespace cellbake
