// Colour helpers shared by the model readers: unit floats to 8-bit channels and
// material x vertex colour modulation, both rounding to nearest.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "stages/geometry.h"

namespace cellbake {

// Maps a colour channel in [0, 1] to 0..255 (clamped, rounded; NaN -> 0).
inline std::uint8_t unit_to_byte(double v) {
  if (!(v > 0)) return 0;
  if (v >= 1) return 255;
  return static_cast<std::uint8_t>(std::lround(v * 255.0));
}

// Channel-wise product of two 8-bit colours, rounded to nearest.
inline Rgba8 modulate(Rgba8 a, Rgba8 b) {
  auto mul = [](unsigned x, unsigned y) { return static_cast<std::uint8_t>((x * y + 127) / 255); };
  return {mul(a.r, b.r), mul(a.g, b.g), mul(a.b, b.b), mul(a.a, b.a)};
}

// The colour of one triangle corner: a vertex colour is modulated by the
// material colour, except under the default material (index 0), whose grey
// only stands in for vertices that have no colour of their own.
inline Rgba8 corner_colour(const Rgba8& material, std::uint32_t material_index, const Rgba8* vertex) {
  if (!vertex) return material;
  return material_index == 0 ? *vertex : modulate(material, *vertex);
}

}  // namespace cellbake
