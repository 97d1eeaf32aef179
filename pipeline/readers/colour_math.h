// Colour helpers shared by the model readers: unit floats to 8-bit channels and
// material x vertex colour modulation, both rounding to nearest.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "pipeline/readers/model_reader.h"
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

// Whether a model's vertex colours carry information: false while every
// colour added so far (R, G, B, A) equals the first.
struct ColourVariation {
  std::uint64_t count = 0;  // colours added
  Rgba8 first{};            // the first one (meaningful when count > 0)
  bool varies = false;
  void add(const Rgba8& c) {
    if (count++ == 0)
      first = c;
    else if (!(c == first))
      varies = true;
  }
};

inline ColourVariation colour_variation(const std::vector<Rgba8>& colours) {
  ColourVariation v;
  for (const Rgba8& c : colours) v.add(c);
  return v;
}

// The colour of one triangle corner: a vertex colour is modulated by the
// material colour, except under the default material (index 0), whose grey
// only stands in for vertices that have no colour of their own. Vertex colours
// that do not vary across the file (`vertex_colours_vary` false: every one
// equal, such as an exporter's default "0 0 0") say nothing and the material
// colour wins; under the default material they are still the colour.
inline Rgba8 corner_colour(const Rgba8& material, std::uint32_t material_index, const Rgba8* vertex,
                           bool vertex_colours_vary) {
  if (!vertex) return material;
  if (material_index == 0) return *vertex;
  return vertex_colours_vary ? modulate(material, *vertex) : material;
}

// Records in `info` what became of the vertex colours seen (`variation`):
// `ignored` when some corner's uniform vertex colour gave way to its
// material's colour.
inline void record_vertex_colour_use(ModelInfo& info, const ColourVariation& variation, bool ignored) {
  if (variation.count == 0) {
    info.vertex_colours = VertexColourUse::none;
  } else if (variation.varies) {
    info.vertex_colours = VertexColourUse::varying;
  } else {
    info.vertex_colours = ignored ? VertexColourUse::uniform_ignored : VertexColourUse::uniform_kept;
    info.uniform_vertex_colour = variation.first;
  }
}

}  // namespace cellbake
