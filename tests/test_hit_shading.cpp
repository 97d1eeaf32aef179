// The Embree backend's hit colours (stages/raycast/hit_shading.h) against the
// light model written out in plain float, in the order the GL shader
// evaluates it: the shader's vectorised path must give the same bits for
// every hit, lit or unlit, with or without vertex colours, normals and
// texels, and for out-of-range and NaN inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "stages/raycast/hit_shading.h"

namespace cellbake {
namespace {

float reference_clamp(float c) {
  if (!(c > 0.0f)) return 0.0f;  // NaN too
  return c < 1.0f ? c : 1.0f;
}

std::uint8_t reference_unorm8(float c) { return std::uint8_t(reference_clamp(c) * 255.0f + 0.5f); }

// hit_shading.h's model, one channel at a time.
Rgba8 reference_shade(const ShadingLights& lights, const SurfaceHit& hit, const std::array<float, 4>* texel) {
  const Chunk& c = *hit.chunk;
  const std::uint32_t* corner = c.indices.data() + 3 * std::size_t(hit.triangle);
  const float w0 = 1.0f - hit.u - hit.v, w1 = hit.u, w2 = hit.v;
  float color[4];
  for (int k = 0; k < 4; ++k) {
    if (c.colors.empty()) {
      const Rgba8 d{};
      const std::uint8_t v[4] = {d.r, d.g, d.b, d.a};
      color[k] = v[k] / 255.0f;
      continue;
    }
    const auto channel = [&](std::uint32_t vertex) {
      const Rgba8& x = c.colors[vertex];
      const std::uint8_t v[4] = {x.r, x.g, x.b, x.a};
      return float(v[k]);
    };
    color[k] =
        (w0 * channel(corner[0]) + w1 * channel(corner[1]) + w2 * channel(corner[2])) * (1.0f / 255.0f);
  }
  if (texel)
    for (int k = 0; k < 3; ++k) color[k] *= (*texel)[std::size_t(k)];
  if (lights.lit) {
    float n[3] = {hit.geometric_normal.x, hit.geometric_normal.y, hit.geometric_normal.z};
    if (!c.normals.empty()) {
      const Vec3f &a = c.normals[corner[0]], &b = c.normals[corner[1]], &d = c.normals[corner[2]];
      n[0] = w0 * a.x + w1 * b.x + w2 * d.x;
      n[1] = w0 * a.y + w1 * b.y + w2 * d.y;
      n[2] = w0 * a.z + w1 * b.z + w2 * d.z;
    }
    const float n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (n2 > 0 && std::isfinite(n2)) {
      const float s = 1.0f / std::sqrt(n2);
      const float key_k[3] = {float(lights.key.x * lights.key_strength),
                              float(lights.key.y * lights.key_strength),
                              float(lights.key.z * lights.key_strength)};
      const float fill_k[3] = {float(lights.fill.x * lights.fill_strength),
                               float(lights.fill.y * lights.fill_strength),
                               float(lights.fill.z * lights.fill_strength)};
      const float key = std::abs((n[0] * key_k[0] + n[1] * key_k[1] + n[2] * key_k[2]) * s);
      const float fill = std::abs((n[0] * fill_k[0] + n[1] * fill_k[1] + n[2] * fill_k[2]) * s);
      const float factor = float(lights.ambient) + key + fill;
      for (int k = 0; k < 3; ++k) color[k] = reference_clamp(color[k] * factor);
    }
  }
  return {reference_unorm8(color[0]), reference_unorm8(color[1]), reference_unorm8(color[2]),
          reference_unorm8(color[3])};
}

// A chunk of `triangles` random triangles over 3 * triangles vertices.
Chunk random_chunk(std::mt19937& rng, int triangles, bool colors, bool normals) {
  std::uniform_int_distribution<int> byte(0, 255);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  Chunk c;
  for (int v = 0; v < 3 * triangles; ++v) {
    c.positions.push_back({gauss(rng), gauss(rng), gauss(rng)});
    if (colors)
      c.colors.push_back({std::uint8_t(byte(rng)), std::uint8_t(byte(rng)), std::uint8_t(byte(rng)),
                          std::uint8_t(byte(rng))});
    if (normals) {
      Vec3f n{gauss(rng), gauss(rng), gauss(rng)};
      const float l = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
      c.normals.push_back({n.x / l, n.y / l, n.z / l});
    }
  }
  for (int v = 0; v < 3 * triangles; ++v) c.indices.push_back(std::uint32_t((v * 7) % (3 * triangles)));
  return c;
}

TEST(HitShading, EveryHitMatchesTheLightModelInPlainFloatBitForBit) {
  std::mt19937 rng(12);
  const ShadingLights lit = shading_lights(ShadingParams{}, Vec3d{0, 0, 1});
  ShadingParams bright;
  bright.ambient = 0.9;  // saturates: the clamp matters
  bright.key_strength = 1.5;
  const ShadingLights saturating = shading_lights(bright, Vec3d{0, 1, 0});
  ShadingParams off;
  off.mode = ShadingMode::unlit;
  const ShadingLights unlit = shading_lights(off, Vec3d{0, 0, 1});
  std::uniform_real_distribution<float> bary(-0.05f, 1.05f), tex(0.0f, 1.2f), normal(-2.0f, 2.0f);
  int checked = 0;
  for (const ShadingLights& lights : {lit, saturating, unlit}) {
    const HitShader shader(lights);
    for (int kind = 0; kind < 4; ++kind) {
      const Chunk chunk = random_chunk(rng, 64, kind & 1, kind & 2);
      for (int i = 0; i < 4000; ++i) {
        SurfaceHit hit;
        hit.chunk = &chunk;
        hit.triangle = std::uint32_t(i % 64);
        hit.u = bary(rng);
        hit.v = bary(rng);
        hit.geometric_normal = i % 17 == 0 ? Vec3f{0, 0, 0} : Vec3f{normal(rng), normal(rng), normal(rng)};
        const std::array<float, 4> texel{tex(rng), tex(rng), tex(rng), tex(rng)};
        const std::array<float, 4>* t = i % 3 == 0 ? &texel : nullptr;
        const Rgba8 want = reference_shade(lights, hit, t), got = shader.shade(hit, t);
        ASSERT_EQ(got, want) << "hit " << i << ", chunk kind " << kind << ": got " << int(got.r) << ","
                             << int(got.g) << "," << int(got.b) << "," << int(got.a) << " want "
                             << int(want.r) << "," << int(want.g) << "," << int(want.b) << "," << int(want.a);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * 4 * 4000);
}

TEST(HitShading, NanAndInfiniteInputsGiveZeroOrOneNeverGarbage) {
  const ShadingLights lights = shading_lights(ShadingParams{}, Vec3d{0, 0, 1});
  const HitShader shader(lights);
  std::mt19937 rng(3);
  const Chunk chunk = random_chunk(rng, 1, true, false);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  SurfaceHit hit;
  hit.chunk = &chunk;
  hit.u = nan;
  hit.v = 0.25f;
  hit.geometric_normal = {0, 0, 1};
  EXPECT_EQ(shader.shade(hit), (Rgba8{0, 0, 0, 0}))
      << "NaN colours are 0, as a GL unorm attachment stores them";
  hit.u = 0.25f;
  hit.geometric_normal = {nan, 0, 1};  // no usable normal: the colour stays unlit
  EXPECT_EQ(shader.shade(hit), reference_shade(lights, hit, nullptr));
  const std::array<float, 4> hot{inf, -inf, nan, 1};
  hit.geometric_normal = {0, 0, 1};
  const Rgba8 got = shader.shade(hit, &hot);
  EXPECT_EQ(got.r, 255);
  EXPECT_EQ(got.g, 0);
  EXPECT_EQ(got.b, 0);
  EXPECT_EQ(got, reference_shade(lights, hit, &hot));
}

}  // namespace
}  // namespace cellbake
