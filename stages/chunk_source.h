// Read access to a chunked geometry store, as the stages see it: a spatial
// query over chunk bounds and loading of one chunk's geometry. Implemented by
// storage::GeometryStore (SQLite R*Tree) and by in-memory fixtures in tests.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/geometry.h"
#include "stages/texture.h"

namespace cellbake {

struct ChunkRef {
  std::int64_t id = 0;
  Box3d bounds;  // conservative world bounds of the chunk's triangles
  std::uint32_t triangle_count = 0;
};

// A simplified version of a chunk (stages/chunk_lod.h): level 1, 2, ... each
// with about half the triangles of the one before, its border vertices kept.
struct ChunkLodRef {
  int level = 0;
  double error = 0;  // metres: how far the simplified surface may lie from the chunk's
  std::uint32_t triangle_count = 0;
};

class ChunkSource {
 public:
  virtual ~ChunkSource() = default;
  // Every chunk whose bounds overlap `box` (touching counts), sorted by id.
  virtual std::vector<ChunkRef> query(const Box3d& box) const = 0;
  // The chunk's geometry; throws std::runtime_error naming the chunk when it is
  // missing or its blob is corrupt. Safe to call from several threads.
  virtual std::shared_ptr<const Chunk> load(std::int64_t id) const = 0;
  // World bounds of the whole model (empty box for an empty model).
  virtual Box3d model_bounds() const = 0;
  // The model's material table, indexed by Chunk::materials (empty: every
  // triangle uses material 0, untextured).
  virtual std::vector<Material> materials() const { return {}; }
  // The texture `id` (a Material::texture_id > 0); throws std::runtime_error
  // naming it when it is missing or corrupt. Safe to call from several threads.
  virtual std::shared_ptr<const TextureImage> load_texture(std::int64_t id) const;
  // The simplified levels stored for chunk `id`, by ascending level (empty:
  // none, e.g. a store ingested before levels were built).
  virtual std::vector<ChunkLodRef> lods(std::int64_t id) const { return {}; }
  // Level `level` (>= 1) of chunk `id`, with Chunk::id = `id`; throws
  // std::runtime_error naming chunk and level when it is missing or corrupt.
  // Safe to call from several threads.
  virtual std::shared_ptr<const Chunk> load_lod(std::int64_t id, int level) const;
};

inline std::shared_ptr<const Chunk> ChunkSource::load_lod(std::int64_t id, int level) const {
  throw std::runtime_error("chunk source has no level " + std::to_string(level) + " of chunk " + std::to_string(id));
}

inline std::shared_ptr<const TextureImage> ChunkSource::load_texture(std::int64_t id) const {
  throw std::runtime_error("chunk source has no texture " + std::to_string(id));
}

}  // namespace cellbake
