#include "stages/far/seen_triangles.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cellbake {

std::vector<std::uint32_t> pixel_tiles(int size) {
  if (size < 1)
    throw std::invalid_argument("seen_triangles: face size must be >= 1, got " + std::to_string(size));
  const std::size_t n = std::size_t(size);
  std::vector<std::uint32_t> tiles(n * n);
  for (std::size_t p = 0; p < tiles.size(); ++p)
    tiles[p] = std::uint32_t(pixel_tile(int(p % n), int(p / n), size));
  return tiles;
}

std::vector<SeenChunk> seen_triangles(std::span<const std::int64_t> chunk,
                                      std::span<const std::uint32_t> triangle,
                                      std::span<const std::uint32_t> tile, SeenScratch& scratch) {
  const std::size_t pixels = chunk.size();
  if (triangle.size() != pixels || tile.size() != pixels)
    throw std::invalid_argument("seen_triangles: " + std::to_string(pixels) + " pixel chunks, " +
                                std::to_string(triangle.size()) + " triangles and " +
                                std::to_string(tile.size()) + " tiles differ");
  if (const auto worst = std::max_element(tile.begin(), tile.end());
      worst != tile.end() && *worst >= std::uint32_t(kFarTilesPerFace))
    throw std::invalid_argument("seen_triangles: tile " + std::to_string(*worst) + " out of range");
  scratch.ranges.clear();
  // Runs alternate between a few chunks (a pipe in front of a wall): a small
  // direct-mapped cache of ranges spares most map lookups.
  constexpr std::size_t kCache = 64;
  std::array<std::int64_t, kCache> cached_id;
  std::array<SeenScratch::Range*, kCache> cached_range{};
  cached_id.fill(-1);
  const auto range_of = [&](std::int64_t id, std::uint32_t t) {
    const std::size_t slot = std::size_t(id) % kCache;
    if (cached_id[slot] != id) {
      cached_id[slot] = id;
      cached_range[slot] = &scratch.ranges.try_emplace(id, SeenScratch::Range{t, t}).first->second;
    }
    return cached_range[slot];
  };
  // The span of triangles each chunk drew. A run of pixels on one chunk keeps
  // its span in registers and stores it when the run ends.
  std::int64_t last = -1;
  SeenScratch::Range* range = nullptr;
  std::uint32_t lo = 0, hi = 0;
  const auto store = [&] {
    if (range) range->lo = std::min(range->lo, lo), range->hi = std::max(range->hi, hi);
  };
  for (std::size_t p = 0; p < pixels; ++p) {
    const std::int64_t id = chunk[p];
    if (id < 0) continue;
    const std::uint32_t t = triangle[p];
    if (id != last) {
      store();
      range = range_of(id, t);
      last = id;
      lo = hi = t;
    }
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  store();
  scratch.by_id.clear();
  for (auto& [id, r] : scratch.ranges) scratch.by_id.emplace_back(id, &r);
  std::sort(scratch.by_id.begin(), scratch.by_id.end());
  std::size_t total = 0;
  for (auto& [id, r] : scratch.by_id) {
    r->offset = total;
    total += std::size_t(r->hi - r->lo) + 1;
  }
  // Padded to whole 64-bit words of masks for the scan below.
  scratch.masks.assign(total + 4, 0);
  last = -1;
  std::size_t base = 0;  // of the current run's chunk: its triangle t's mask is masks[base + t] (modulo 2^64)
  for (std::size_t p = 0; p < pixels; ++p) {
    const std::int64_t id = chunk[p];
    if (id < 0) continue;
    if (id != last) {
      const SeenScratch::Range& r = *range_of(id, 0);  // every id is in the map by now
      base = r.offset - std::size_t(r.lo);
      last = id;
    }
    scratch.masks[base + triangle[p]] |= std::uint16_t(1u << tile[p]);
  }
  // Each chunk's span, four masks at a time: faces see chunks in part, so
  // most of a span is zero.
  std::vector<SeenChunk> seen(scratch.by_id.size());
  for (std::size_t c = 0; c < seen.size(); ++c) {
    const auto& [id, r] = scratch.by_id[c];
    SeenChunk& out = seen[c];
    out.id = id;
    const std::uint16_t* span = scratch.masks.data() + r->offset;
    const std::uint32_t count = r->hi - r->lo + 1;
    for (std::uint32_t i = 0; i < count; i += 4) {
      std::uint64_t word;
      std::memcpy(&word, span + i, sizeof word);
      if (word == 0) continue;
      for (std::uint32_t j = i; j < std::min(count, i + 4); ++j)
        if (const std::uint16_t m = span[j]) {
          out.triangles.push_back(r->lo + j);
          out.triangle_tiles.push_back(m);
          out.tiles |= m;
        }
    }
  }
  return seen;
}

}  // namespace cellbake
