// Spatial chunking: splits a model's triangles into chunks of at most
// `max_triangles` spatially coherent triangles by recursive median kd-splits
// on the longest axis of the centroid bounds, and assembles chunk geometry
// (deduplicated vertices, float32 positions relative to a double origin).
// References: Wald & Havran, "On building fast kd-trees for ray tracing" (2006)
// for median splits; Wilson thesis §7.3.1.1 for per-cell loading of geometry.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

// One triangle's sort key: centroid (double, so translated models split
// identically), a hash of its canonical vertex set (to find exact duplicates)
// and its index in input order.
struct TriangleKey {
  Vec3d centroid;
  std::uint64_t shape_hash = 0;
  std::uint32_t index = 0;
};

struct ChunkRange {
  std::size_t begin = 0, end = 0;  // into the reordered key array
};

// Reorders `keys` so every returned range is one chunk, ranges in kd-tree
// order (spatially coherent), keys inside a range sorted by index. Exact
// duplicates (same centroid and shape hash) are never split across ranges.
// Deterministic: depends only on the key values. Ranges hold <= max_triangles
// keys unless a run of identical triangles is larger.
std::vector<ChunkRange> split_into_chunks(std::vector<TriangleKey>& keys, std::size_t max_triangles);

// Canonical key of a triangle: centroid and a hash of its sorted vertices.
TriangleKey make_triangle_key(const Triangle& t, std::uint32_t index);

// True when the triangle has (relatively) zero area: collinear or coincident
// corners, judged as |cross| <= 1e-12 * (longest edge)^2 in double.
bool is_degenerate(const Triangle& t);

// True when both triangles have the same three corner positions (any order).
bool same_corners(const Triangle& a, const Triangle& b);

// Builds a chunk from triangles given in their final order: vertices shared by
// identical (position, colour, uv, normal), origin = centre of the chunk's
// bounds, materials kept only when some triangle has a non-zero material, uvs
// only when some corner has a non-zero uv, normals only when some triangle
// has them (then every corner gets one: the source's, or its face normal when
// the triangle has none or a zero one), quantised to the store's octahedral
// 16-bit code (stages/normal_packing.h) so a stored chunk reads back exactly.
Chunk build_chunk(const std::vector<const Triangle*>& triangles);

}  // namespace cellbake
