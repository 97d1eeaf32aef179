// A model as seen from one cell at a coarse resolution: each chunk at the
// coarsest of its stored levels (stages/chunk_lod.h) within `error_px` pixels
// of a `face_size` cube face seen from the nearest point of the cell, the
// chunk itself where no level is that close. What a check that resamples a
// cell's far field at a few dozen pixels a face (storage/face_image_check.h)
// traces instead of the whole model, so its cost no longer grows with the
// model's triangles (82 M: levels of a few million).
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <vector>

#include "stages/chunk_source.h"

namespace cellbake {

class LevelChunkSource final : public ChunkSource {
 public:
  // `base` must outlive this source.
  LevelChunkSource(const ChunkSource& base, const Box3d& cell, double error_px, int face_size);

  // The base's chunks, each ref's triangle_count that of the level load() gives.
  std::vector<ChunkRef> query(const Box3d& box) const override;
  // The chosen level of chunk `id` (Chunk::id = id), or the chunk itself.
  std::shared_ptr<const Chunk> load(std::int64_t id) const override;
  Box3d model_bounds() const override { return base_.model_bounds(); }
  std::vector<Material> materials() const override { return base_.materials(); }
  std::shared_ptr<const TextureImage> load_texture(std::int64_t id) const override { return base_.load_texture(id); }
  // Levels of levels are not offered: what load() gives is final.

 private:
  struct Choice {
    int level = 0;
    std::uint32_t triangles = 0;
  };
  Choice choose(const ChunkRef& ref) const;  // caller holds mutex_

  const ChunkSource& base_;
  Box3d cell_;
  double error_px_;
  int face_size_;
  mutable std::mutex mutex_;
  mutable std::map<std::int64_t, Choice> chosen_;  // by chunk id, filled by query()
};

}  // namespace cellbake
