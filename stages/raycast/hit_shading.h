// The colour of a ray hit, computed as ChunkRenderer's fragment shader does
// (the light model of stages/shading.h), so that the Embree and GL
// sampling backends produce the same pixels:
//   base  = the triangle's vertex colours at the hit's barycentric coordinates
//           (barycentric in 3D = GL's perspective-correct interpolation);
//   n     = the chunk's per-vertex normals at the hit, normalised, when it has
//           them, else the flat face normal;
//   rgb   = clamp(base * (ambient + |n . key| * key_strength + |n . fill| * fill_strength), 0, 1)
//           (unlit: base as it is; a zero normal also keeps base), alpha = base alpha,
// in float and rounded to 8 bits like a GL unorm colour attachment.
// Textures enter as a texel multiplying the base colour's rgb
// (stages/raycast/hit_texturing.h computes it).
#pragma once

#include <array>
#include <cstdint>

#include "stages/geometry.h"
#include "stages/shading.h"

namespace cellbake {

// One ray hit on a chunk triangle, with Embree's barycentric convention:
// point = (1 - u - v) p0 + u p1 + v p2 for corners p0, p1, p2 = indices
// 3 * triangle + 0, 1, 2.
struct SurfaceHit {
  const Chunk* chunk = nullptr;
  std::uint32_t triangle = 0;
  float u = 0, v = 0;
  Vec3f geometric_normal;  // any length and orientation (Embree's Ng)
};

// Cache hints for shading hits in a stream (no effect on any result): the
// vertex indices of `triangle`, and the colours, normals and uvs of its
// corners that HitShader::shade and the texturer read. A shading loop asks for
// the indices some hits ahead and the attributes fewer hits ahead, so the
// dependent loads (index, then attribute) overlap with shading earlier hits.
// Inline: called twice per ray.
inline void prefetch_triangle_indices(const Chunk& chunk, std::uint32_t triangle) {
  __builtin_prefetch(chunk.indices.data() + 3 * std::size_t(triangle));
}
inline void prefetch_corner_attributes(const Chunk& chunk, std::uint32_t triangle) {
  const std::uint32_t* corner = chunk.indices.data() + 3 * std::size_t(triangle);
  for (int k = 0; k < 3; ++k) {
    if (!chunk.colors.empty()) __builtin_prefetch(chunk.colors.data() + corner[k]);
    if (!chunk.normals.empty()) __builtin_prefetch(chunk.normals.data() + corner[k]);
    if (!chunk.uvs.empty()) __builtin_prefetch(chunk.uvs.data() + corner[k]);
  }
}

class HitShader {
 public:
  // Throws std::invalid_argument for non-unit directions or negative or
  // non-finite strengths (the checks of ChunkRenderer::set_shading).
  explicit HitShader(const ShadingLights& lights);
  // The pixel colour of `hit` (chunk set, triangle in range); with `texel`,
  // the base colour's rgb is multiplied by its rgb first (a textured material,
  // stages/raycast/hit_texturing.h), as the GL shader does.
  Rgba8 shade(const SurfaceHit& hit, const std::array<float, 4>* texel = nullptr) const;

 private:
  // The lighting factor ambient + |n . key| + |n . fill| at the hit (corner:
  // its triangle's three vertex indices; w0..w2: its barycentric weights);
  // false when the normal there is zero or not finite (the colour stays unlit).
  bool lit_factor(const SurfaceHit& hit, const std::uint32_t* corner, float w0, float w1, float w2,
                  float& factor) const;

  bool lit_;
  float key_[3], fill_[3], ambient_;  // directions times strengths, as the shader's uniforms
};

}  // namespace cellbake
