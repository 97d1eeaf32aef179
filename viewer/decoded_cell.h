// A view cell ready to draw: its cull box and near-field chunk list, and every
// face of every panoramic sample decoded (textured depth mesh + colour image).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/encode.h"
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
// chunk of the geometry store, drawn under a cache id of its own.
struct DecodedFarPiece {
  std::int64_t cache_id = 0;  // negative and unique per cell and piece, so GPU caches keep it apart from the store's chunks
  std::int64_t chunk_id = 0;  // the store's chunk
  Box3d bounds;               // world bounds of the piece's triangles
  std::vector<std::uint32_t> triangles;  // ascending numbers into the stored chunk (empty when `chunk` is set)
  std::shared_ptr<const Chunk> chunk;    // the piece itself, for cells that stored it as a chunk blob
};

// The chunk a far piece draws: `piece.chunk`, or the piece's triangles cut
// out of `stored` (the store's chunk `piece.chunk_id`), with id = cache_id.
// Throws std::runtime_error naming the chunk when a triangle number is out of
// range for `stored`.
std::shared_ptr<const Chunk> far_piece_chunk(const DecodedFarPiece& piece, const Chunk& stored);

struct DecodedCell {
  std::int64_t id = 0;
  Box3d bounds;
  Box3d cull_box;                     // cube of cull_half_size around the cell centre
  std::vector<std::int64_t> near_ids;  // chunks of the near field, in stored order
  std::uint64_t near_triangles = 0;    // triangles of those chunks inside the cull box
  std::uint64_t far_triangles = 0;     // sum over the decoded faces
  std::vector<DecodedFace> faces;
  // Exact far geometry (issue #13): the seen triangles of far chunks, and
  // whole chunks of the store.
  std::vector<DecodedFarPiece> far_pieces;
  std::vector<std::int64_t> far_whole_ids;  // ascending
  std::uint64_t far_geometry_triangles = 0;
  std::vector<SampleNode> samples;  // eye, dependency-tree parent and triangles of every sample
  std::size_t bytes() const;  // decoded size in host memory
};

// Decodes `row` (loaded with blobs). Throws std::runtime_error naming the cell,
// sample and face when the cell is not "done", a face index is out of range,
// a blob is corrupt or truncated (the validated decoders of stages/encode.h),
// or far geometry bounds are inverted or not finite: the caller then falls
// back for this cell alone. With `source` (the cell's geometry store), the far
// pieces are also cut out of their stored chunks here (far_piece_chunk), off
// the drawing thread, with bounds of the triangles cut; a triangle number out
// of range, a chunk the store lacks or a whole chunk not where and as the row
// says is an error naming the cell; without it they are cut when first drawn.
DecodedCell decode_cell(const CellRow& row, const ChunkSource* source = nullptr);

}  // namespace cellbake
