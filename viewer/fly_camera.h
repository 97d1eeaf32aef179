// Fly / walk navigation for the interactive viewer: a position plus yaw and
// pitch about the model's up axis. Walk mode moves only horizontally and
// keeps the eye `eye_height` above `floor` (the model's lowest point along up).
#pragma once

#include "stages/render/chunk_renderer.h"

namespace cellbake {

struct FlyCamera {
  Vec3d position;
  Vec3d up{0, 0, 1};   // the model's up axis (unit, +z or +y)
  double yaw_deg = 0;  // about `up`, 0 = along the first horizontal axis (x for z-up, z for y-up)
  double pitch_deg = 0;
  double speed = 2;    // model units per second
  bool walk = false;
  double eye_height = 1.7;
  double floor = 0;    // position along `up` of the ground in walk mode

  // Unit view direction.
  Vec3d forward() const;
  // Moves by `speed * seconds` along forward (or its horizontal part when
  // walking), right and up (ignored when walking), each input in [-1, 1].
  void move(double ahead, double right, double rise, double seconds);
  // Turns by the given angles; pitch is clamped to [-89, 89] degrees.
  void turn(double yaw_delta_deg, double pitch_delta_deg);
  // The render camera for a width x height view with vertical fov `fov_y_deg`.
  RenderCamera camera(double fov_y_deg, int width, int height, double near_plane) const;
};

}  // namespace cellbake
