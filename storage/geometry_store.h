// The chunked geometry store: an SQLite file with one row per chunk (geometry
// blob + exact double bounds and origin), an R*Tree over chunk bounds, model
// metadata, source files and materials. Schema: docs/database.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "stages/chunk_lod.h"
#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

class Hasher;
class SqliteDb;
class SqliteStatement;

struct SourceFileRecord {
  std::string path;
  std::uint64_t bytes = 0;
  std::string hash;  // xxh3-128 of the file bytes, hex
  std::uint64_t triangles = 0;
};

struct StoreSummary {
  Box3d bounds;
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  std::uint64_t chunks = 0;
  std::uint64_t skipped_degenerate = 0;
  std::uint64_t skipped_duplicate = 0;
  std::string units = "m";
  std::string content_hash;  // GeometryStoreWriter::content_hash(): over what the store holds, hex
  // The model's up axis as ingest recorded it: "z", "y", or "" when unknown
  // (meta `up`, absent then; not part of content_hash), and what said so
  // (meta `up_source`, e.g. "glTF: Y-up by specification", "--up").
  std::string up;
  std::string up_source;
};

// Writes a new store into a temporary file next to `final_path` and renames it
// over `final_path` only in finish(): an interrupted ingest never leaves a
// half-written store that looks valid, and an existing store stays untouched.
// The constructor throws std::runtime_error naming the path when something
// other than an empty file or a geometry store is there (a cell database, a
// device, a directory, a symbolic link: never replaced), and removes
// `STORE.tmp-PID` / `STORE.spill-PID` files of killed ingests (the process is
// gone and the file untouched for 10 minutes).
class GeometryStoreWriter {
 public:
  explicit GeometryStoreWriter(const std::filesystem::path& final_path);
  ~GeometryStoreWriter();  // removes the temporary file unless finished

  void add_material(std::uint32_t index, const Material& material);
  // Stores `image` (losslessly, as PNG) and returns its id (1, 2, 3 ... in
  // call order) for Material::texture_id; `source` names where it came from.
  std::int64_t add_texture(const TextureImage& image, const std::string& source);
  void add_source(const SourceFileRecord& source);
  // Adds a chunk (its id is assigned here, 1, 2, 3 ... in call order).
  std::int64_t add_chunk(const Chunk& chunk);
  // Adds the simplified levels of chunk `id` (already added; table
  // chunk_lods, part of content_hash() when any are added). Throws
  // std::invalid_argument for a chunk id not added yet.
  void add_chunk_lods(std::int64_t id, const std::vector<ChunkLod>& lods);
  // The content hash (32 hex digits) of what has been added: every texture
  // (id, size, wrap modes, alpha flag, texels), every material row (index,
  // name, colour, texture name and id, alpha test) and every chunk row (id,
  // origin, bounds, counts, blob), each kind in call order (= id order when
  // materials are added by ascending index, as ingest does). Sources, units
  // and the up axis are metadata, not content. Whatever changes what a bake
  // reads from the store changes it (geometry, a material colour in a .mtl, a
  // texture's texels), and only that. stored_content_hash() recomputes it
  // from a finished store.
  std::string content_hash() const;
  // Writes the metadata (with the row counts of chunks, R-tree entries,
  // materials and textures: meta `rows`, checked by check_store_rows before a
  // bake), commits, and atomically renames onto the final path.
  void finish(const StoreSummary& summary);

 private:
  std::filesystem::path final_path_, temp_path_;
  std::unique_ptr<SqliteDb> db_;
  std::unique_ptr<SqliteStatement> insert_chunk_, insert_rtree_, insert_lod_;
  std::uint64_t lod_rows_ = 0;
  std::int64_t next_id_ = 1;
  std::int64_t next_texture_id_ = 1;
  std::uint64_t material_rows_ = 0;
  std::unique_ptr<Hasher> textures_hash_, materials_hash_, chunks_hash_, lods_hash_;
  std::size_t pending_ = 0;
  bool finished_ = false;
};

// Read-only access; a ChunkSource for the stages. Thread-safe: a small pool of
// connections plus an LRU cache of decoded chunks capped at `cache_bytes`.
class GeometryStore : public ChunkSource {
 public:
  explicit GeometryStore(const std::filesystem::path& path, std::size_t cache_bytes = 512u << 20);
  ~GeometryStore() override;

  std::vector<ChunkRef> query(const Box3d& box) const override;
  std::shared_ptr<const Chunk> load(std::int64_t id) const override;
  Box3d model_bounds() const override { return summary_.bounds; }
  // The levels table (read once at open; empty for stores without levels).
  std::vector<ChunkLodRef> lods(std::int64_t id) const override;
  // Decoded and cached like chunks; throws naming store, chunk and level.
  std::shared_ptr<const Chunk> load_lod(std::int64_t id, int level) const override;

  const StoreSummary& summary() const { return summary_; }
  std::vector<SourceFileRecord> sources() const;
  // The material table (read once at open).
  std::vector<Material> materials() const override;
  // Decodes texture `id` from the store (no cache here: renderers keep their
  // own bounded caches of what they upload).
  std::shared_ptr<const TextureImage> load_texture(std::int64_t id) const override;
  // 1 or 2 (docs/database.md).
  int schema_version() const { return schema_version_; }
  std::vector<ChunkRef> all_chunks() const;
  // How many textures the store holds (0 for schema 1).
  std::uint64_t texture_count() const;
  const std::filesystem::path& path() const { return path_; }

 private:
  struct Connection;
  std::unique_ptr<Connection> acquire() const;
  void release(std::unique_ptr<Connection> c) const;

  std::vector<Material> read_materials(SqliteDb& db) const;
  std::shared_ptr<const Chunk> cached(std::int64_t key) const;
  std::shared_ptr<const Chunk> remember(std::int64_t key, std::shared_ptr<const Chunk> chunk) const;

  std::filesystem::path path_;
  StoreSummary summary_;
  int schema_version_ = 2;
  std::vector<Material> materials_;
  std::unordered_map<std::int64_t, std::vector<ChunkLodRef>> lods_;
  mutable std::mutex pool_mutex_;
  mutable std::vector<std::unique_ptr<Connection>> pool_;

  std::size_t cache_cap_;
  mutable std::mutex cache_mutex_;
  mutable std::size_t cache_bytes_ = 0;
  mutable std::list<std::int64_t> lru_;
  struct CacheEntry {
    std::shared_ptr<const Chunk> chunk;
    std::list<std::int64_t>::iterator pos;
    std::size_t bytes;
  };
  mutable std::unordered_map<std::int64_t, CacheEntry> cache_;
};

// Recomputes a finished store's content hash from its rows, as
// GeometryStoreWriter::content_hash() computed it while writing (equal for
// stores written since that hash; earlier stores hashed their source files).
// Throws std::runtime_error naming the path when the file is not a schema 2
// store or a texture does not decode.
std::string stored_content_hash(const std::filesystem::path& path);

// The table names and row counts meta `rows` records ("chunks=N chunk_rtree=N
// materials=N textures=N"), in that order.
inline constexpr const char* kStoreCountedTables[] = {"chunks", "chunk_rtree", "materials", "textures"};

}  // namespace cellbake
