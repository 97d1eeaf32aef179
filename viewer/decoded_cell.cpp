#include "viewer/decoded_cell.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "stages/chunk_subset.h"
#include "stages/encode/encode_triangle_list.h"
#include "storage/chunk_codec.h"
#include "storage/far_geometry_check.h"

namespace cellbake {

std::size_t DecodedCell::bytes() const {
  std::size_t b = (near_ids.size() + far_whole_ids.size()) * sizeof(std::int64_t);
  for (const DecodedFarPiece& p : far_pieces) {
    b += sizeof(DecodedFarPiece) + p.triangles.size() * sizeof(std::uint32_t);
    if (const Chunk* c = p.chunk.get())
      b += c->positions.size() * (sizeof(Vec3f) + sizeof(Rgba8)) + c->uvs.size() * sizeof(Uv) +
           c->normals.size() * sizeof(Vec3f) + (c->indices.size() + c->materials.size()) * sizeof(std::uint32_t);
  }
  for (const DecodedFace& f : faces)
    b += f.mesh.positions.size() * sizeof(Vec3f) + f.mesh.uvs.size() * sizeof(Uv) +
         f.mesh.indices.size() * sizeof(std::uint32_t) + f.image.pixels.size() * sizeof(Rgba8);
  return b;
}

std::int64_t lod_cache_id(std::int64_t chunk_id, int level) {
  constexpr std::int64_t kLevelBase = std::int64_t{1} << 62, kChunkLimit = std::int64_t{1} << 58;
  static_assert(kMaxFarGeometryLevel < 16, "a level's cache id holds it in 4 bits");
  if (level < 1 || level > kMaxFarGeometryLevel || chunk_id < 1 || chunk_id >= kChunkLimit)
    throw std::invalid_argument("far geometry of chunk " + std::to_string(chunk_id) + " level " +
                                std::to_string(level) + ": no cache id (levels 1.." +
                                std::to_string(kMaxFarGeometryLevel) + " of chunks 1..2^58-1)");
  return kLevelBase + chunk_id * 16 + level;
}

std::shared_ptr<const Chunk> far_piece_chunk(const DecodedFarPiece& piece, const ChunkSource& source) {
  if (piece.chunk) return piece.chunk;
  const std::string at = "far geometry of chunk " + std::to_string(piece.chunk_id);
  if (piece.level != 0) {
    const std::string level = at + " level " + std::to_string(piece.level) + ": ";
    std::shared_ptr<const Chunk> loaded;
    try {
      loaded = source.load_lod(piece.chunk_id, piece.level);
    } catch (const std::exception& e) {
      throw std::runtime_error(level + e.what());
    }
    if (!loaded) throw std::runtime_error(level + "the store returned no geometry");
    auto chunk = std::make_shared<Chunk>(*loaded);
    chunk->id = piece.cache_id;
    return chunk;
  }
  const std::shared_ptr<const Chunk> stored = source.load(piece.chunk_id);
  try {
    auto chunk = std::make_shared<Chunk>(chunk_subset(*stored, piece.triangles));
    chunk->id = piece.cache_id;
    return chunk;
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(at + ": " + e.what() + " (the cell does not belong to this geometry store?)");
  }
}

std::uint32_t far_piece_triangles(const DecodedFarPiece& piece, const ChunkSource& source) {
  if (piece.chunk) return std::uint32_t(piece.chunk->triangle_count());
  if (piece.level == 0) return std::uint32_t(piece.triangles.size());
  for (const ChunkLodRef& l : source.lods(piece.chunk_id))
    if (l.level == piece.level) return l.triangle_count;
  return 0;
}

namespace {

// Reorders the face's triangles tile by tile (stable within a tile) on a
// kFaceTiles^2 grid over its texture coordinates (the face's image plane) and
// records each non-empty tile's index range and world bounds.
void split_into_tiles(DecodedFace& d) {
  const FaceMesh& m = d.mesh;
  const std::size_t triangles = m.triangle_count();
  constexpr int kTiles = kFaceTiles * kFaceTiles;
  std::vector<int> tile_of(triangles);
  std::array<std::uint32_t, kTiles> count{};
  for (std::size_t t = 0; t < triangles; ++t) {
    float u = 0, v = 0;
    for (int c = 0; c < 3; ++c) u += m.uvs[m.indices[3 * t + c]].u, v += m.uvs[m.indices[3 * t + c]].v;
    const int tu = std::clamp(int(u / 3 * kFaceTiles), 0, kFaceTiles - 1), tv = std::clamp(int(v / 3 * kFaceTiles), 0, kFaceTiles - 1);
    tile_of[t] = tv * kFaceTiles + tu;
    ++count[std::size_t(tile_of[t])];
  }
  std::array<std::uint32_t, kTiles> start{};
  for (int k = 1; k < kTiles; ++k) start[std::size_t(k)] = start[std::size_t(k) - 1] + count[std::size_t(k) - 1];
  std::vector<std::uint32_t> indices(m.indices.size());
  std::array<Box3d, kTiles> bounds;
  std::array<std::uint32_t, kTiles> next = start;
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::size_t k = std::size_t(tile_of[t]);
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t i = m.indices[3 * t + c];
      indices[3 * std::size_t(next[k]) + c] = i;
      const Vec3f& p = m.positions[i];
      bounds[k].expand(d.eye + Vec3d{p.x, p.y, p.z});
    }
    ++next[k];
  }
  d.mesh.indices = std::move(indices);
  d.tiles.clear();
  for (int k = 0; k < kTiles; ++k)
    if (count[std::size_t(k)] > 0)
      d.tiles.push_back({3 * start[std::size_t(k)], 3 * count[std::size_t(k)], bounds[std::size_t(k)]});
}

// A level row (far_geometry_level_problem passed) as a piece under its shared
// cache id; with `source`, checked against its levels and loaded.
DecodedFarPiece decode_level_piece(const FarGeometryRow& g, const std::string& where,
                                   const ChunkSource* source) {
  const std::string at = where + " far geometry of chunk " + std::to_string(g.chunk_id) + " level " +
                         std::to_string(g.level) + ": ";
  DecodedFarPiece piece;
  piece.chunk_id = g.chunk_id;
  piece.level = g.level;
  piece.bounds = g.bounds;
  try {
    piece.cache_id = lod_cache_id(g.chunk_id, g.level);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + " " + e.what());
  }
  if (!source) return piece;  // loaded when first drawn
  std::vector<ChunkLodRef> lods;
  try {
    lods = source->lods(g.chunk_id);
  } catch (const std::exception& e) {
    throw std::runtime_error(at + e.what());
  }
  const auto it =
      std::find_if(lods.begin(), lods.end(), [&](const ChunkLodRef& l) { return l.level == g.level; });
  if (it == lods.end())
    throw std::runtime_error(at +
                             "the store holds no such level of the chunk (the cell does not belong to this "
                             "geometry store?)");
  if (it->triangle_count != g.triangles)
    throw std::runtime_error(at + std::to_string(g.triangles) + " triangles, the store's level has " +
                             std::to_string(it->triangle_count) +
                             " (the cell does not belong to this geometry store?)");
  try {
    piece.chunk = far_piece_chunk(piece, *source);  // names chunk and level
  } catch (const std::exception& e) {
    throw std::runtime_error(where + " " + e.what());
  }
  piece.bounds = piece.chunk->bounds;  // of the level's triangles, whatever the row says
  return piece;
}

}  // namespace

DecodedCell decode_cell(const CellRow& row, const ChunkSource* source) {
  const std::string where = "cell " + std::to_string(row.id);
  if (row.status != "done") throw std::runtime_error(where + " is not baked (status " + row.status + ")");
  DecodedCell cell;
  cell.id = row.id;
  cell.bounds = row.bounds;
  cell.cull_box = Box3d::cube(row.bounds.center(), row.cull_half_size);
  cell.near_triangles = row.near_triangles;
  for (const NearChunkRow& n : row.near_chunks) cell.near_ids.push_back(n.chunk_id);
  for (std::size_t k = 0; k < row.far_geometry.size(); ++k) {
    const FarGeometryRow& g = row.far_geometry[k];
    cell.far_geometry_triangles += g.triangles;
    const std::string far = where + " far geometry of chunk " + std::to_string(g.chunk_id) + ": ";
    if (!is_finite(g.bounds.lo) || !is_finite(g.bounds.hi) || g.bounds.lo.x > g.bounds.hi.x ||
        g.bounds.lo.y > g.bounds.hi.y || g.bounds.lo.z > g.bounds.hi.z)
      throw std::runtime_error(far + "bounds are inverted or not finite (culled, it would never be drawn)");
    if (const std::string problem = far_geometry_level_problem(g); !problem.empty())
      throw std::runtime_error(where + " " + problem);
    if (g.level != 0) {
      cell.far_pieces.push_back(decode_level_piece(g, where, source));
      continue;
    }
    if (g.whole) {
      // The store's chunk, where the row's bounds say, with the row's triangles
      // (the index entry alone: the chunk is loaded when it is drawn).
      if (source) {
        bool found = false;
        for (const ChunkRef& r : source->query(g.bounds))
          if (r.id == g.chunk_id) {
            if (r.triangle_count != g.triangles)
              throw std::runtime_error(far + "whole, " + std::to_string(g.triangles) + " triangles, the store's chunk has " +
                                       std::to_string(r.triangle_count) + " (the cell does not belong to this geometry store?)");
            found = true;
          }
        if (!found)
          throw std::runtime_error(far + "the store holds no such chunk within the row's bounds (the cell does not "
                                         "belong to this geometry store?)");
      }
      cell.far_whole_ids.push_back(g.chunk_id);
      continue;
    }
    DecodedFarPiece piece;
    piece.cache_id = -(row.id * (std::int64_t{1} << 20)) - std::int64_t(k) - 1;
    piece.chunk_id = g.chunk_id;
    piece.bounds = g.bounds;
    try {
      if (is_triangle_list_blob(g.geometry)) {
        piece.triangles = decode_triangle_list(g.geometry);
        if (piece.triangles.size() != g.triangles) throw std::runtime_error("triangle count differs from the row's");
      } else {  // a chunk blob of its own (far_choice version 2)
        auto chunk = std::make_shared<Chunk>();
        decode_chunk_blob(g.geometry.data(), g.geometry.size(), *chunk);
        chunk->id = piece.cache_id;
        chunk->origin = g.origin;
        chunk->bounds = g.bounds;
        piece.chunk = std::move(chunk);
      }
      if (source && !piece.chunk) {
        piece.chunk = far_piece_chunk(piece, *source);
        piece.triangles = {};
        piece.bounds = piece.chunk->bounds;  // of the triangles cut out, whatever the row says
      }
    } catch (const std::exception& e) {
      throw std::runtime_error(far + e.what());
    }
    cell.far_pieces.push_back(std::move(piece));
  }
  std::sort(cell.far_whole_ids.begin(), cell.far_whole_ids.end());
  for (const SampleRow& s : row.samples) {
    SampleNode node;
    node.index = s.index;
    node.eye = s.eye;
    node.parent = s.parent;
    for (const FaceRow& f : s.faces) {
      const std::string face = where + " sample " + std::to_string(s.index) + " face " + std::to_string(f.face);
      if (f.face < 0 || f.face >= kCubeFaces) throw std::runtime_error(face + ": face index out of range");
      if (f.image_format == kNoFaceImage) {  // nothing of this face is drawn
        std::size_t triangles = 0;
        try {
          triangles = decode_face_mesh(f.mesh).triangle_count();
        } catch (const std::exception& e) {
          throw std::runtime_error(face + ": " + e.what());
        }
        if (!f.image.empty()) throw std::runtime_error(face + ": stores no image but an image blob");
        if (f.triangles != 0 || triangles != 0)
          throw std::runtime_error(face + ": stores no image but " + std::to_string(std::max<std::size_t>(f.triangles, triangles)) +
                                   " triangles");
        continue;
      }
      DecodedFace d;
      d.sample = s.index;
      d.face = f.face;
      d.eye = s.eye;
      try {
        d.mesh = decode_face_mesh(f.mesh);
        d.image = decode_image(f.image);
      } catch (const std::exception& e) {
        throw std::runtime_error(face + ": " + e.what());
      }
      for (const Uv& uv : d.mesh.uvs)
        if (!(uv.u >= 0 && uv.u <= 1 && uv.v >= 0 && uv.v <= 1))
          throw std::runtime_error(face + ": texture coordinate outside [0, 1]");
      for (const Vec3f& p : d.mesh.positions) d.bounds.expand(s.eye + Vec3d{p.x, p.y, p.z});
      split_into_tiles(d);
      cell.far_triangles += d.mesh.triangle_count();
      node.triangles += d.mesh.triangle_count();
      cell.faces.push_back(std::move(d));
    }
    cell.samples.push_back(node);
  }
  return cell;
}

}  // namespace cellbake
