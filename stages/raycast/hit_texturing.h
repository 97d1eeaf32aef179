// Material textures at ray hits, as ChunkRenderer's fragment shader applies
// them: the hit triangle's material (Chunk::materials, index into the model's
// table) names a texture; its texel at the barycentric texture coordinates is
// filtered trilinearly (stages/texture_sampling.h) at the level of detail of
// the pixel's footprint, multiplies the vertex colour's rgb, and drops the hit
// when the material alpha-tests and the texel's alpha is below 0.5.
//
// Level of detail: GL takes lambda = log2 of the longer screen-space
// derivative of the texel coordinates (per 2 x 2 pixel quad). Here the same
// derivatives come from ray differentials (Igehy 1999, "Tracing ray
// differentials", SIGGRAPH): a one-pixel step along the face's right or up
// axis at the hit's planar depth, slid along the ray onto the triangle's
// plane, expressed in the triangle's edges and mapped through its texture
// coordinates. Per pixel rather than per quad, so lambda may differ from
// llvmpipe's by the change of the derivatives across one pixel.
#pragma once

#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/raycast/hit_shading.h"
#include "stages/texture_sampling.h"

namespace cellbake {

// Decoded textures with their mip chains, shared by every sampling thread of
// a bake, bounded in bytes (least recently used evicted; a texture in use by
// some thread stays alive until it lets go). Thread-safe.
class MipTextureCache {
 public:
  explicit MipTextureCache(std::size_t cap_bytes) : cap_bytes_(cap_bytes) {}
  // Texture `id` of `source`, decoded and mipmapped on first use. Throws what
  // source.load_texture throws. Ids are per model: one cache per bake.
  std::shared_ptr<const TextureMips> get(std::int64_t id, const ChunkSource& source);
  std::size_t bytes() const;

 private:
  struct Entry {
    std::shared_ptr<const TextureMips> mips;
    std::list<std::int64_t>::iterator recency;
  };
  std::size_t cap_bytes_;
  mutable std::mutex mutex_;
  std::size_t bytes_ = 0;
  std::unordered_map<std::int64_t, Entry> entries_;
  std::list<std::int64_t> lru_;
};

// What texturing does to one hit.
struct HitTexel {
  bool textured = false;  // the hit's material has a texture (and the chunk uvs)
  bool dropped = false;   // alpha-tested away: the ray goes on behind it
  Rgbaf texel{1, 1, 1, 1};
};

// Per cube map: the model's materials and the textures they use.
class HitTexturer {
 public:
  HitTexturer(const ChunkSource& source, MipTextureCache& cache);
  // True when no material has a texture (then texel() is never needed).
  bool untextured() const { return untextured_; }
  // The texel for `hit` on the ray t * dir (dir with forward component 1, so
  // t is the planar depth), where one pixel step is `step_x` / `step_y` in
  // the image plane at unit depth (the face's right and up axes times 2 /
  // render size).
  HitTexel texel(const SurfaceHit& hit, const Vec3f& dir, float t, const Vec3f& step_x, const Vec3f& step_y) const;

 private:
  const ChunkSource& source_;
  MipTextureCache& cache_;
  std::vector<Material> materials_;
  bool untextured_ = true;
  // Per cube map: the textures already fetched (keeps them alive while tracing).
  mutable std::unordered_map<std::int64_t, std::shared_ptr<const TextureMips>> in_use_;
};

}  // namespace cellbake
