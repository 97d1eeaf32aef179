// Test cameras for ChunkRenderer frames.
#pragma once

#include "stages/render/chunk_renderer.h"

namespace cellbake::test {

// Looking straight down -z from `eye`, image x along +x and y along +y, with
// a square frustum of half-angle tangent `tan_half`.
inline RenderCamera camera_down(const Vec3d& eye, double tan_half = 0.1) {
  RenderCamera c;
  c.eye = eye;
  c.forward = {0, 0, -1};
  c.right = {1, 0, 0};
  c.up = {0, 1, 0};
  c.tan_left = c.tan_bottom = -tan_half;
  c.tan_right = c.tan_top = tan_half;
  return c;
}

}  // namespace cellbake::test
