#include "pipeline/level_chunk_source.h"

#include "stages/chunk_lod.h"

namespace cellbake {

LevelChunkSource::LevelChunkSource(const ChunkSource& base, const Box3d& cell, double error_px, int face_size)
    : base_(base), cell_(cell), error_px_(error_px), face_size_(face_size) {}

LevelChunkSource::Choice LevelChunkSource::choose(const ChunkRef& ref) const {
  if (const auto known = chosen_.find(ref.id); known != chosen_.end()) return known->second;
  Choice c{0, ref.triangle_count};
  const std::vector<ChunkLodRef> levels = base_.lods(ref.id);
  if (!levels.empty()) {
    const double allowed = allowed_lod_error(box_distance(cell_, ref.bounds), error_px_, face_size_);
    if (const int level = choose_lod_level(levels, allowed); level > 0)
      for (const ChunkLodRef& l : levels)
        if (l.level == level) c = {level, l.triangle_count};
  }
  chosen_.emplace(ref.id, c);
  return c;
}

std::vector<ChunkRef> LevelChunkSource::query(const Box3d& box) const {
  std::vector<ChunkRef> refs = base_.query(box);
  const std::lock_guard<std::mutex> lock(mutex_);
  for (ChunkRef& r : refs) r.triangle_count = choose(r).triangles;
  return refs;
}

std::shared_ptr<const Chunk> LevelChunkSource::load(std::int64_t id) const {
  int level = 0;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (const auto known = chosen_.find(id); known != chosen_.end()) level = known->second.level;
  }
  return level > 0 ? base_.load_lod(id, level) : base_.load(id);
}

}  // namespace cellbake
