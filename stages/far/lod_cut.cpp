#include "stages/far/lod_cut.h"

#include <algorithm>
#include <limits>

#include "stages/chunk_lod.h"

namespace cellbake {

LodCut lod_cut_at_error(std::span<const LodCutChunk> chunks, double error_px) {
  LodCut cut;
  cut.error_px = error_px;
  cut.levels.reserve(chunks.size());
  for (const LodCutChunk& c : chunks) {
    const int level = c.pixel_size > 0 ? choose_lod_level(c.levels, error_px * c.pixel_size) : 0;
    std::uint32_t triangles = c.triangles;
    for (const ChunkLodRef& l : c.levels)
      if (l.level == level) triangles = l.triangle_count;
    cut.levels.push_back(level);
    cut.triangles += triangles;
  }
  return cut;
}

LodCut lod_cut_for_triangles(std::span<const LodCutChunk> chunks, std::uint64_t max_triangles) {
  // Every threshold at which some chunk may change level: a level's error in its chunk's pixels.
  std::vector<double> thresholds{0.0};
  for (const LodCutChunk& c : chunks)
    if (c.pixel_size > 0)
      for (const ChunkLodRef& l : c.levels) thresholds.push_back(l.error / c.pixel_size);
  std::sort(thresholds.begin(), thresholds.end());
  thresholds.erase(std::unique(thresholds.begin(), thresholds.end()), thresholds.end());
  // Triangles never grow with the threshold: the first threshold that fits, by bisection.
  std::size_t lo = 0, hi = thresholds.size() - 1;
  if (lod_cut_at_error(chunks, thresholds[hi]).triangles > max_triangles) return lod_cut_at_error(chunks, thresholds[hi]);
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (lod_cut_at_error(chunks, thresholds[mid]).triangles <= max_triangles)
      hi = mid;
    else
      lo = mid + 1;
  }
  return lod_cut_at_error(chunks, thresholds[lo]);
}

}  // namespace cellbake
