// Two-sided Lambert over two directional lights plus ambient (the model of
// stages/shading.h), evaluated per ray hit in float as the GL fragment
// shader of stages/render/chunk_renderer.cpp does.
#include "stages/raycast/hit_shading.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cellbake {
#if !defined(__SSE2__)
namespace {

// c limited to [0, 1] (NaN: 0).
float unit_clamp(float c) {
  const float low = c > 0.0f ? c : 0.0f;
  return low < 1.0f ? low : 1.0f;
}

// Round to nearest, as a GL unorm8 colour attachment stores a float.
std::uint8_t to_unorm8(float c) { return static_cast<std::uint8_t>(unit_clamp(c) * 255.0f + 0.5f); }

}  // namespace
#endif

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

#if defined(__SSE2__)

// The SSE2 path (every x86-64): the four channels in one register. Every
// lane sees the operations of the scalar path below in the same order (no
// fused multiply-adds on SSE2), so both give the same bits; max(x, 0) then
// min(x, 1) limits to [0, 1] with NaN giving 0, without the branches GCC
// puts around any clamp written in C++ (shaded colours fall on either side
// of the limits unpredictably: the mispredictions cost ~2.5 % of a cube map).
Rgba8 HitShader::shade(const SurfaceHit& hit, const std::array<float, 4>* texel) const {
  const Chunk& c = *hit.chunk;
  const std::uint32_t* corner = c.indices.data() + 3 * std::size_t(hit.triangle);
  const float w0 = 1.0f - hit.u - hit.v, w1 = hit.u, w2 = hit.v;
  __m128 color;
  if (c.colors.empty()) {
    const Rgba8 d{};
    color = _mm_set_ps(d.a / 255.0f, d.b / 255.0f, d.g / 255.0f, d.r / 255.0f);
  } else {
    static_assert(sizeof(Rgba8) == 4, "a vertex colour is loaded as one 32-bit word, r in its low byte");
    const __m128i zero = _mm_setzero_si128();
    const auto channels = [&](std::uint32_t vertex) {
      std::uint32_t bits;
      std::memcpy(&bits, &c.colors[vertex], sizeof bits);
      const __m128i bytes = _mm_cvtsi32_si128(int(bits));
      return _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes, zero), zero));
    };
    const __m128 c0 = channels(corner[0]), c1 = channels(corner[1]), c2 = channels(corner[2]);
    color =
        _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(w0), c0), _mm_mul_ps(_mm_set1_ps(w1), c1)),
                              _mm_mul_ps(_mm_set1_ps(w2), c2)),
                   _mm_set1_ps(1.0f / 255.0f));
  }
  if (texel) color = _mm_mul_ps(color, _mm_set_ps(1.0f, (*texel)[2], (*texel)[1], (*texel)[0]));
  if (lit_) {
    float factor;
    if (lit_factor(hit, corner, w0, w1, w2, factor))
      color = _mm_mul_ps(color, _mm_set_ps(1.0f, factor, factor, factor));
  }
  color = _mm_min_ps(_mm_max_ps(color, _mm_setzero_ps()), _mm_set1_ps(1.0f));
  const __m128i unorm =
      _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(color, _mm_set1_ps(255.0f)), _mm_set1_ps(0.5f)));
  const __m128i words = _mm_packs_epi32(unorm, unorm);
  const std::uint32_t bits = std::uint32_t(_mm_cvtsi128_si32(_mm_packus_epi16(words, words)));
  return {std::uint8_t(bits), std::uint8_t(bits >> 8), std::uint8_t(bits >> 16), std::uint8_t(bits >> 24)};
}

#else

Rgba8 HitShader::shade(const SurfaceHit& hit, const std::array<float, 4>* texel) const {
  const Chunk& c = *hit.chunk;
  const std::uint32_t* corner = c.indices.data() + 3 * std::size_t(hit.triangle);
  const float w0 = 1.0f - hit.u - hit.v, w1 = hit.u, w2 = hit.v;
  std::array<float, 4> color;
  if (c.colors.empty()) {
    const Rgba8 d{};
    color = {d.r / 255.0f, d.g / 255.0f, d.b / 255.0f, d.a / 255.0f};
  } else {
    const Rgba8 &c0 = c.colors[corner[0]], &c1 = c.colors[corner[1]], &c2 = c.colors[corner[2]];
    const auto mix = [&](std::uint8_t a, std::uint8_t b, std::uint8_t d) {
      return (w0 * a + w1 * b + w2 * d) * (1.0f / 255.0f);
    };
    color = {mix(c0.r, c1.r, c2.r), mix(c0.g, c1.g, c2.g), mix(c0.b, c1.b, c2.b), mix(c0.a, c1.a, c2.a)};
  }
  if (texel)
    for (int k = 0; k < 3; ++k) color[std::size_t(k)] *= (*texel)[std::size_t(k)];
  float factor;
  if (lit_ && lit_factor(hit, corner, w0, w1, w2, factor))
    for (int k = 0; k < 3; ++k) color[std::size_t(k)] *= factor;
  return {to_unorm8(color[0]), to_unorm8(color[1]), to_unorm8(color[2]), to_unorm8(color[3])};
}

#endif

bool HitShader::lit_factor(const SurfaceHit& hit, const std::uint32_t* corner, float w0, float w1, float w2,
                           float& factor) const {
  float n[3] = {hit.geometric_normal.x, hit.geometric_normal.y, hit.geometric_normal.z};
  const Chunk& c = *hit.chunk;
  if (!c.normals.empty()) {
    const Vec3f &n0 = c.normals[corner[0]], &n1 = c.normals[corner[1]], &n2 = c.normals[corner[2]];
    n[0] = w0 * n0.x + w1 * n1.x + w2 * n2.x;
    n[1] = w0 * n0.y + w1 * n1.y + w2 * n2.y;
    n[2] = w0 * n0.z + w1 * n1.z + w2 * n2.z;
  }
  const float n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  if (!(n2 > 0 && std::isfinite(n2))) return false;
  const float s = 1.0f / std::sqrt(n2);
  const float key = std::abs((n[0] * key_[0] + n[1] * key_[1] + n[2] * key_[2]) * s);
  const float fill = std::abs((n[0] * fill_[0] + n[1] * fill_[1] + n[2] * fill_[2]) * s);
  factor = ambient_ + key + fill;
  return true;
}

}  // namespace cellbake
