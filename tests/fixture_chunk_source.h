// In-memory ChunkSource for tests and benchmarks: chunks built from coloured
// world-space Triangle records, a linear-scan query sorted by id, and a log of
// load() calls so tests can check that a stage loads only the chunks it needs.
// No gtest dependency. (tests/fixture_memory_chunk_source.h is a sibling
// fixture built from bare corner triples.)
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake::test {

// A triangle with one flat colour.
inline Triangle flat_triangle(Vec3d a, Vec3d b, Vec3d c, Rgba8 color) {
  Triangle t;
  t.p = {a, b, c};
  t.color = {color, color, color};
  return t;
}

// Builds chunk `id` from world-space triangles (three unshared vertices each,
// per-corner colours kept), with float positions relative to `origin`.
inline Chunk chunk_from_triangles(std::int64_t id, const std::vector<Triangle>& triangles, const Vec3d& origin) {
  Chunk chunk;
  chunk.id = id;
  chunk.origin = origin;
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec3d r = t.p[static_cast<std::size_t>(k)] - origin;
      chunk.indices.push_back(static_cast<std::uint32_t>(chunk.positions.size()));
      chunk.positions.push_back({static_cast<float>(r.x), static_cast<float>(r.y), static_cast<float>(r.z)});
      chunk.colors.push_back(t.color[static_cast<std::size_t>(k)]);
    }
  }
  // Bounds of the stored (float-rounded) corners, so they are conservative for what is drawn.
  for (std::uint32_t v = 0; v < chunk.positions.size(); ++v) chunk.bounds.expand(chunk.world(v));
  return chunk;
}

// Same, with the origin at the centre of the triangles' bounds.
inline Chunk chunk_from_triangles(std::int64_t id, const std::vector<Triangle>& triangles) {
  Box3d bounds;
  for (const Triangle& t : triangles)
    for (const Vec3d& p : t.p) bounds.expand(p);
  return chunk_from_triangles(id, triangles, bounds.empty() ? Vec3d{} : bounds.center());
}

class InMemoryChunkSource final : public ChunkSource {
 public:
  // Adds (or replaces) a chunk.
  void add(Chunk chunk) {
    const std::int64_t id = chunk.id;
    chunks_[id] = std::make_shared<const Chunk>(std::move(chunk));
  }

  std::vector<ChunkRef> query(const Box3d& box) const override {
    std::vector<ChunkRef> refs;  // std::map iterates in id order
    for (const auto& [id, chunk] : chunks_)
      if (!chunk->bounds.empty() && chunk->bounds.overlaps(box))
        refs.push_back({id, chunk->bounds, static_cast<std::uint32_t>(chunk->triangle_count())});
    return refs;
  }

  std::shared_ptr<const Chunk> load(std::int64_t id) const override {
    auto it = chunks_.find(id);
    if (it == chunks_.end()) throw std::runtime_error("fixture: chunk " + std::to_string(id) + " missing");
    std::lock_guard lock(mutex_);
    loads_.push_back(id);
    return it->second;
  }

  Box3d model_bounds() const override {
    Box3d bounds;
    for (const auto& [id, chunk] : chunks_) bounds.expand(chunk->bounds);
    return bounds;
  }

  // Every id passed to load() so far, in call order.
  std::vector<std::int64_t> loads() const {
    std::lock_guard lock(mutex_);
    return loads_;
  }
  void clear_loads() {
    std::lock_guard lock(mutex_);
    loads_.clear();
  }

 private:
  std::map<std::int64_t, std::shared_ptr<const Chunk>> chunks_;
  mutable std::mutex mutex_;
  mutable std::vector<std::int64_t> loads_;
};

}  // namespace cellbake::test
