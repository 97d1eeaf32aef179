// A view cell ready to draw: its cull box and near-field chunk list, and every
// face of every panoramic sample decoded (textured depth mesh + colour image).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/encode/encode.h"
#include "stages/geometry.h"
#include "storage/cell_db.h"
#include "viewer/sample_selection.h"

namespace cellbake {

// A tile of a face mesh: a run of its triangles (after decode_cell reorders
// them tile by tile) and their world bounds, so a view draws only the tiles
// it can see (the thesis kept an octree of the meshes for the same purpose).
struct FaceTile {
  std::uint32_t first_index = 0, index_count = 0;
  Box3d bounds;
};

struct DecodedFace {
  int sample = 0, face = 0;
  Vec3d eye;  // the sample's eye; mesh positions are relative to it
  Box3d bounds;  // world bounds of the mesh (empty for an empty mesh)
  FaceMesh mesh;  // triangles ordered tile by tile
  DecodedImage image;
  std::vector<FaceTile> tiles;  // non-empty tiles of a kFaceTiles x kFaceTiles grid over the face (by triangle centroid)
};

constexpr int kFaceTiles = kFarTiles;  // the far-choice grid (stages/cube_map.h)

// A piece of a cell's exact far geometry (issue #13): some triangles of a
// chunk of the geometry store, drawn under a cache id of its own; or a
// simplified level of a whole chunk (issue #35), drawn under a cache id
// shared by every cell that draws that level.
struct DecodedFarPiece {
  // Level 0: negative and unique per cell and piece, so GPU caches keep it
  // apart from the store's chunks; level >= 1: lod_cache_id(chunk_id, level).
  std::int64_t cache_id = 0;
  std::int64_t chunk_id = 0;  // the store's chunk
  int level = 0;              // 0: triangles of the chunk itself; >= 1: the store's level (load_lod)
  Box3d bounds;               // world bounds of the piece's triangles
  std::vector<std::uint32_t> triangles;  // ascending numbers into the stored chunk (level 0, `chunk` unset)
  std::shared_ptr<const Chunk> chunk;    // the piece itself: stored as a chunk blob, or already cut / loaded
};

// The GPU cache id of level `level` of store chunk `chunk_id`:
// 2^62 + chunk_id * 16 + level. Store chunk ids are small positive numbers
// and per-cell pieces' ids negative, so it collides with neither, and every
// cell drawing the same chunk level shares one cache entry. Throws
// std::invalid_argument naming chunk and level unless 1 <= level <=
// kMaxFarGeometryLevel (15) and 1 <= chunk_id < 2^58.
std::int64_t lod_cache_id(std::int64_t chunk_id, int level);

// The chunk a far piece draws, with id = cache_id: `piece.chunk`; else for a
// level piece `source`'s level (ChunkSource::load_lod) of the chunk; else the
// piece's triangles cut out of `source`'s chunk `piece.chunk_id`. Throws
// std::runtime_error naming the chunk (and level) when the source lacks it or
// a triangle number is out of range for the stored chunk.
std::shared_ptr<const Chunk> far_piece_chunk(const DecodedFarPiece& piece, const ChunkSource& source);

// The triangles `piece` draws: its chunk's when cut or loaded already, else
// its triangle numbers' count (level 0) or the level's count `source` lists
// (0 when the source lists no such level). Loads nothing.
std::uint32_t far_piece_triangles(const DecodedFarPiece& piece, const ChunkSource& source);

struct DecodedCell {
  std::int64_t id = 0;
  Box3d bounds;
  Box3d cull_box;                     // cube of cull_half_size around the cell centre
  std::vector<std::int64_t> near_ids;  // chunks of the near field, in stored order
  std::uint64_t near_triangles = 0;    // triangles of those chunks inside the cull box
  std::uint64_t far_triangles = 0;     // sum over the decoded faces
  std::vector<DecodedFace> faces;
  // Exact far geometry (issue #13): the seen triangles of far chunks and
  // simplified levels of whole chunks (issue #35), and whole chunks of the store.
  std::vector<DecodedFarPiece> far_pieces;
  std::vector<std::int64_t> far_whole_ids;  // ascending
  std::uint64_t far_geometry_triangles = 0;
  std::vector<SampleNode> samples;  // eye, dependency-tree parent and triangles of every sample
  std::size_t bytes() const;  // decoded size in host memory
};

// Decodes `row` (loaded with blobs). Throws std::runtime_error naming the cell,
// sample and face when the cell is not "done", a face index is out of range,
// a blob is corrupt or truncated (the validated decoders of stages/encode/encode.h),
// or far geometry bounds are inverted or not finite, or a row's level is
// damaged (far_geometry_level_problem): the caller then falls back for this
// cell alone. With `source` (the cell's geometry store), the far pieces are
// also cut out of their stored chunks or loaded as their levels here
// (far_piece_chunk), off the drawing thread, with bounds of the triangles cut
// or loaded; a triangle number out of range, a chunk the store lacks, a whole
// chunk not where and as the row says, or a level the store does not list for
// the chunk with the row's triangle count is an error naming the cell, chunk
// and level; without it they are cut or loaded when first drawn.
DecodedCell decode_cell(const CellRow& row, const ChunkSource* source = nullptr);

}  // namespace cellbake
