// Unit normals packed into two signed 16-bit integers (12 significant bits
// each) by the octahedral
// mapping (Meyer et al. 2010, "On floating-point normal vectors", EGSR;
// Cigolle et al. 2014, "A survey of efficient representations for independent
// unit vectors", JCGT 3(2)): the sphere is projected onto the octahedron
// |x| + |y| + |z| = 1 and its lower half folded over the upper, so the square
// [-1, 1]^2 covers every direction with a worst-case angular error of about
// 0.05 degrees at 12 bits a component.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "stages/geometry.h"

namespace cellbake {

// Code units per unit: 12 bits a component, far below what the light model
// can show; the small integers compress better in the vertex codec than full
// 16-bit codes (measured in docs/benchmark-history.md).
inline constexpr float kOctScale = 2047.f;

// The octahedral code of `n` (any non-zero finite vector; it is normalised by
// its L1 norm). A zero or non-finite vector packs to +z.
inline std::array<std::int16_t, 2> pack_normal_oct16(Vec3f n) {
  const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 0) || !std::isfinite(l1)) return {0, 0};
  float x = n.x / l1, y = n.y / l1;
  if (n.z < 0) {
    const float fx = (1 - std::abs(y)) * (x >= 0 ? 1.f : -1.f);
    const float fy = (1 - std::abs(x)) * (y >= 0 ? 1.f : -1.f);
    x = fx;
    y = fy;
  }
  const auto quantise = [](float v) {
    return static_cast<std::int16_t>(std::lround(std::clamp(v, -1.f, 1.f) * kOctScale));
  };
  return {quantise(x), quantise(y)};
}

// The unit vector of an octahedral code (every code is valid).
inline Vec3f unpack_normal_oct16(std::array<std::int16_t, 2> code) {
  float x = std::max(code[0] / kOctScale, -1.f), y = std::max(code[1] / kOctScale, -1.f);
  const float z = 1 - std::abs(x) - std::abs(y);
  if (z < 0) {
    const float fx = (1 - std::abs(y)) * (x >= 0 ? 1.f : -1.f);
    const float fy = (1 - std::abs(x)) * (y >= 0 ? 1.f : -1.f);
    x = fx;
    y = fy;
  }
  const float len = std::sqrt(x * x + y * y + z * z);
  return {x / len, y / len, z / len};
}

// `n` as it comes back from the store: packed and unpacked once.
inline Vec3f quantise_normal(Vec3f n) { return unpack_normal_oct16(pack_normal_oct16(n)); }

}  // namespace cellbake
