// Cube-map conventions shared by the sampler, the depth-mesh builder and the
// viewer. Six 90-degree faces in the order +X, -X, +Y, -Y, +Z, -Z. Pixel (i, j)
// of an N x N face has row j = 0 at the top; its centre maps to the direction
//   forward + s * right + t * up,  s = 2 (i + 0.5) / N - 1,  t = 1 - 2 (j + 0.5) / N.
// Depth is *planar view depth* (distance along `forward`, float32, linear),
// so the world point of a pixel is eye + depth * (forward + s right + t up).
// Background (no geometry) is +infinity.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

constexpr int kCubeFaces = 6;
constexpr float kBackgroundDepth = std::numeric_limits<float>::infinity();

struct FaceBasis {
  Vec3d forward, right, up;  // right = forward x up, as for an OpenGL camera (right x up = -forward)
};

// The basis of cube face `face` (0..5). Faces share edges exactly: the border
// directions of neighbouring faces coincide.
inline FaceBasis cube_face_basis(int face) {
  switch (face) {
    case 0: return {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}};   // +X
    case 1: return {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};   // -X
    case 2: return {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}};    // +Y
    case 3: return {{0, -1, 0}, {-1, 0, 0}, {0, 0, 1}};  // -Y
    case 4: return {{0, 0, 1}, {-1, 0, 0}, {0, 1, 0}};   // +Z
    default: return {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}};  // -Z
  }
}

// Direction (not normalised, forward component 1) through face coordinates (s, t) in [-1, 1].
inline Vec3d cube_face_direction(const FaceBasis& b, double s, double t) {
  return b.forward + b.right * s + b.up * t;
}

// Each face is split into kFarTiles x kFarTiles tiles (row-major, row 0 at
// the top): the grid the far field's representation is chosen on
// (stages/far/far_choice.h) and viewers cull depth meshes with.
constexpr int kFarTiles = 4;
constexpr int kFarTilesPerFace = kFarTiles * kFarTiles;

// The tile (row * kFarTiles + column) holding the centre of pixel (col, row)
// of a size x size face.
inline int pixel_tile(int col, int row, int size) {
  const auto band = [size](int i) { return int((2 * std::int64_t(i) + 1) * kFarTiles / (2 * std::int64_t(size))); };
  return band(row) * kFarTiles + band(col);
}

// A chunk a cube face shows, with the tiles (bits pixel_tile) it may reach:
// either the whole chunk (`triangles` empty: a source that knows only which
// chunks it drew) or the triangles that drew pixels, ascending, each with the
// tiles it drew in (both sampling backends know: the ray caster's hits, the
// rasteriser's primitive ids; stages/far/seen_triangles.h).
struct SeenChunk {
  std::int64_t id = 0;
  std::uint32_t tiles = 0;
  std::vector<std::uint32_t> triangles;
  std::vector<std::uint16_t> triangle_tiles;  // parallel to `triangles`
  bool whole() const { return triangles.empty(); }
  bool operator==(const SeenChunk&) const = default;
};

// One rendered cube face: row-major, row 0 at the top.
struct CubeFace {
  int size = 0;
  std::vector<Rgba8> color;
  std::vector<float> depth;  // planar view depth; kBackgroundDepth where nothing was drawn
  // Every chunk that drew a pixel here (a backend may list more: hidden ones
  // it could not rule out), sorted by id: what exact far geometry standing
  // in for this face's depth mesh must draw.
  std::vector<SeenChunk> seen;
};

// A panoramic colour + depth sample taken at `eye` (world coordinates).
struct CubeSample {
  Vec3d eye;
  std::array<CubeFace, kCubeFaces> faces;
};

// A mesh for one cube face, positions relative to the sample's eye (float32 is
// enough there: the eye carries the world offset), texture coordinates into
// that face's colour image (u right, v down, both in [0, 1]).
struct FaceMesh {
  std::vector<Vec3f> positions;
  std::vector<Uv> uvs;
  std::vector<std::uint32_t> indices;
  std::size_t triangle_count() const { return indices.size() / 3; }
};

}  // namespace cellbake
