// Two-sided Lambert over two directional lights plus ambient (the model of
// stages/render/shading.h), evaluated per ray hit in float as the GL fragment
// shader of stages/render/chunk_renderer.cpp does.
#include "stages/raycast/hit_shading.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace cellbake {
namespace {

// c limited to [0, 1] (NaN: 0). On x86-64 with SSE's maxss and minss: the
// compiler turns any clamp written in C++ into branches around the
// conversion below, and shaded colours fall on either side of the limits
// unpredictably (the mispredictions cost ~2.5 % of a cube map).
float unit_clamp(float c) {
#if defined(__SSE__)
  return _mm_cvtss_f32(_mm_min_ss(_mm_max_ss(_mm_set_ss(c), _mm_setzero_ps()), _mm_set_ss(1.0f)));
#else
  const float low = c > 0.0f ? c : 0.0f;
  return low < 1.0f ? low : 1.0f;
#endif
}

// Round to nearest, as a GL unorm8 colour attachment stores a float.
std::uint8_t to_unorm8(float c) { return static_cast<std::uint8_t>(unit_clamp(c) * 255.0f + 0.5f); }

}  // namespace

HitShader::HitShader(const ShadingLights& l) {
  const auto finite_unit = [](const Vec3d& v) { return is_finite(v) && std::abs(length(v) - 1) < 1e-6; };
  const auto strength = [](double s) { return s >= 0 && std::isfinite(s); };
  if (!finite_unit(l.key) || !finite_unit(l.fill) || !strength(l.key_strength) || !strength(l.fill_strength) ||
      !strength(l.ambient))
    throw std::invalid_argument("hit_shading: shading needs unit light directions and finite strengths >= 0");
  lit_ = l.lit;
  for (int k = 0; k < 3; ++k) {
    key_[k] = static_cast<float>(l.key[k] * l.key_strength);
    fill_[k] = static_cast<float>(l.fill[k] * l.fill_strength);
  }
  ambient_ = static_cast<float>(l.ambient);
}

std::array<float, 4> HitShader::base_color(const SurfaceHit& hit) const {
  const Chunk& c = *hit.chunk;
  if (c.colors.empty()) {
    const Rgba8 d{};
    return {d.r / 255.0f, d.g / 255.0f, d.b / 255.0f, d.a / 255.0f};
  }
  const std::size_t i = 3 * std::size_t(hit.triangle);
  const Rgba8 &c0 = c.colors[c.indices[i]], &c1 = c.colors[c.indices[i + 1]], &c2 = c.colors[c.indices[i + 2]];
  const float w0 = 1.0f - hit.u - hit.v, w1 = hit.u, w2 = hit.v;
  constexpr float kUnorm = 1.0f / 255.0f;
  const auto mix = [&](std::uint8_t a, std::uint8_t b, std::uint8_t d) { return (w0 * a + w1 * b + w2 * d) * kUnorm; };
  return {mix(c0.r, c1.r, c2.r), mix(c0.g, c1.g, c2.g), mix(c0.b, c1.b, c2.b), mix(c0.a, c1.a, c2.a)};
}

Rgba8 HitShader::shade(const SurfaceHit& hit, const std::array<float, 4>* texel) const {
  std::array<float, 4> color = base_color(hit);
  if (texel)
    for (int k = 0; k < 3; ++k) color[std::size_t(k)] *= (*texel)[std::size_t(k)];
  if (lit_) {
    float n[3] = {hit.geometric_normal.x, hit.geometric_normal.y, hit.geometric_normal.z};
    const Chunk& c = *hit.chunk;
    if (!c.normals.empty()) {
      const std::size_t i = 3 * std::size_t(hit.triangle);
      const Vec3f &n0 = c.normals[c.indices[i]], &n1 = c.normals[c.indices[i + 1]], &n2 = c.normals[c.indices[i + 2]];
      const float w0 = 1.0f - hit.u - hit.v, w1 = hit.u, w2 = hit.v;
      n[0] = w0 * n0.x + w1 * n1.x + w2 * n2.x;
      n[1] = w0 * n0.y + w1 * n1.y + w2 * n2.y;
      n[2] = w0 * n0.z + w1 * n1.z + w2 * n2.z;
    }
    const float n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (n2 > 0 && std::isfinite(n2)) {
      const float s = 1.0f / std::sqrt(n2);
      const float key = std::abs((n[0] * key_[0] + n[1] * key_[1] + n[2] * key_[2]) * s);
      const float fill = std::abs((n[0] * fill_[0] + n[1] * fill_[1] + n[2] * fill_[2]) * s);
      const float factor = ambient_ + key + fill;
      for (int k = 0; k < 3; ++k) color[std::size_t(k)] = unit_clamp(color[std::size_t(k)] * factor);
    }
  }
  return {to_unorm8(color[0]), to_unorm8(color[1]), to_unorm8(color[2]), to_unorm8(color[3])};
}

}  // namespace cellbake
