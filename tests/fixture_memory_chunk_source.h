// An in-memory ChunkSource for tests and benchmarks: chunks are held in a
// vector, query() is a linear scan over their bounds, load() counts its calls;
// simplified levels of chunks (lods(), load_lod()) are held in a map the test fills.
// Header-only, no GoogleTest dependency (the benchmarks use it too).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake::test {

// Builds a chunk from world-space triangles (three corners each, unshared
// vertices) stored float32 relative to `origin`; bounds are the exact world
// bounds of the stored (rounded) corners, so they are conservative.
inline Chunk make_memory_chunk(std::int64_t id, const std::vector<std::array<Vec3d, 3>>& triangles,
                               const Vec3d& origin = {}) {
  Chunk chunk;
  chunk.id = id;
  chunk.origin = origin;
  for (const auto& t : triangles)
    for (const Vec3d& p : t) {
      chunk.indices.push_back(static_cast<std::uint32_t>(chunk.positions.size()));
      chunk.positions.push_back({static_cast<float>(p.x - origin.x), static_cast<float>(p.y - origin.y),
                                 static_cast<float>(p.z - origin.z)});
      chunk.colors.push_back({});
    }
  for (std::uint32_t v = 0; v < chunk.positions.size(); ++v) chunk.bounds.expand(chunk.world(v));
  return chunk;
}

// Recomputes `chunk.bounds` from its stored positions (for hand-built chunks).
inline void compute_memory_chunk_bounds(Chunk& chunk) {
  chunk.bounds = Box3d{};
  for (std::uint32_t v = 0; v < chunk.positions.size(); ++v) chunk.bounds.expand(chunk.world(v));
}

class MemoryChunkSource : public ChunkSource {
 public:
  // Adds a chunk; its id must be unique and its bounds already set.
  void add(Chunk chunk) {
    auto it = std::lower_bound(chunks_.begin(), chunks_.end(), chunk.id,
                               [](const auto& c, std::int64_t v) { return c->id < v; });
    if (it != chunks_.end() && (*it)->id == chunk.id)
      throw std::invalid_argument("MemoryChunkSource: duplicate chunk id " + std::to_string(chunk.id));
    bounds_.expand(chunk.bounds);
    chunks_.insert(it, std::make_shared<const Chunk>(std::move(chunk)));
  }

  std::vector<ChunkRef> query(const Box3d& box) const override {
    std::vector<ChunkRef> refs;
    for (const auto& c : chunks_)
      if (!c->bounds.empty() && c->bounds.overlaps(box))
        refs.push_back({c->id, c->bounds, static_cast<std::uint32_t>(c->triangle_count())});
    return refs;
  }

  std::shared_ptr<const Chunk> load(std::int64_t id) const override {
    loads_.fetch_add(1, std::memory_order_relaxed);
    auto it = std::lower_bound(chunks_.begin(), chunks_.end(), id,
                               [](const auto& c, std::int64_t v) { return c->id < v; });
    if (it == chunks_.end() || (*it)->id != id)
      throw std::runtime_error("MemoryChunkSource: chunk " + std::to_string(id) + " is missing");
    return *it;
  }

  Box3d model_bounds() const override { return bounds_; }

  // Adds level `level` (>= 1) of chunk `id` as lods() lists it: `error` and
  // the chunk's triangle count (`triangle_count` overrides it, for tests of a
  // source that misreports). Its Chunk::id is set to `id`; replaces an earlier one.
  void add_lod(std::int64_t id, int level, Chunk chunk, double error = 0,
               std::optional<std::uint32_t> triangle_count = std::nullopt) {
    if (level < 1) throw std::invalid_argument("MemoryChunkSource: level " + std::to_string(level) + " < 1");
    chunk.id = id;
    const auto triangles = triangle_count.value_or(static_cast<std::uint32_t>(chunk.triangle_count()));
    lods_[{id, level}] = {ChunkLodRef{level, error, triangles},
                          std::make_shared<const Chunk>(std::move(chunk))};
  }

  std::vector<ChunkLodRef> lods(std::int64_t id) const override {
    std::vector<ChunkLodRef> refs;  // ascending: the map orders by (id, level)
    for (auto it = lods_.lower_bound({id, 0}); it != lods_.end() && it->first.first == id; ++it)
      refs.push_back(it->second.ref);
    return refs;
  }

  std::shared_ptr<const Chunk> load_lod(std::int64_t id, int level) const override {
    lod_loads_.fetch_add(1, std::memory_order_relaxed);
    auto it = lods_.find({id, level});
    if (it == lods_.end())
      throw std::runtime_error("MemoryChunkSource: level " + std::to_string(level) + " of chunk " +
                               std::to_string(id) + " is missing");
    return it->second.chunk;
  }

  std::uint64_t load_count() const { return loads_.load(std::memory_order_relaxed); }
  std::size_t chunk_count() const { return chunks_.size(); }
  std::uint64_t lod_load_count() const { return lod_loads_.load(std::memory_order_relaxed); }

 private:
  std::vector<std::shared_ptr<const Chunk>> chunks_;  // sorted by id
  Box3d bounds_;
  mutable std::atomic<std::uint64_t> loads_{0};
  struct Lod {
    ChunkLodRef ref;
    std::shared_ptr<const Chunk> chunk;
  };
  std::map<std::pair<std::int64_t, int>, Lod> lods_;  // by (chunk id, level)
  mutable std::atomic<std::uint64_t> lod_loads_{0};
};

}  // namespace cellbake::test
