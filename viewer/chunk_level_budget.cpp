#include "viewer/chunk_level_budget.h"

#include "stages/chunk_lod.h"
#include "stages/far/lod_cut.h"

namespace cellbake {

std::vector<int> levels_for_triangle_budget(std::span<const ChunkDrawItem> items, const ChunkSource& source,
                                            const Vec3d& eye, double metres_per_pixel_per_metre,
                                            std::uint64_t max_triangles) {
  std::vector<int> levels;
  levels.reserve(items.size());
  for (const ChunkDrawItem& item : items) levels.push_back(item.level);
  if (max_triangles == 0) return levels;
  std::uint64_t total = 0;
  for (const ChunkDrawItem& item : items) total += item.triangles;
  if (total <= max_triangles) return levels;
  std::vector<LodCutChunk> chunks;
  chunks.reserve(items.size());
  for (const ChunkDrawItem& item : items) {
    LodCutChunk c;
    c.pixel_size = box_distance(Box3d{eye, eye}, item.bounds) * metres_per_pixel_per_metre;
    c.triangles = item.triangles;
    for (const ChunkLodRef& l : source.lods(item.chunk_id))
      if (l.level > item.level && l.triangle_count < item.triangles) c.levels.push_back(l);
    chunks.push_back(std::move(c));
  }
  const LodCut cut = lod_cut_for_triangles(chunks, max_triangles);
  for (std::size_t i = 0; i < items.size(); ++i)
    if (cut.levels[i] > 0) levels[i] = cut.levels[i];
  return levels;
}

}  // namespace cellbake
