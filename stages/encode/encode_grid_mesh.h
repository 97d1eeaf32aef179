// Stage `encode`, grid face meshes (face mesh blob version 2): a depth-mesh
// vertex is a pixel corner (i, j) of its cube face plus a planar depth, so it
// is coded as two small integers and a log-quantised depth, predicted from
// the already decoded neighbours (parallelogram rule, Touma & Gotsman 1998,
// "Triangle Mesh Compression"; depth from the plane of the adjacent
// triangle), with meshoptimizer's index codec for connectivity and zstd over
// the streams. Internal to encode_face_mesh.cpp / decode_face_mesh.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "stages/cube_map.h"

namespace cellbake {

inline constexpr std::uint8_t kGridMeshVersion = 2;

// Encodes `mesh` as a version-2 blob when every vertex lies on the eye ray
// through a pixel corner of face `face` (0..5) of a `face_size`-pixel face
// (uv = corner / face_size, positive planar depth), as build_depth_meshes and
// simplify_face_mesh make them; std::nullopt otherwise (the caller falls back
// to version 1). Triangles are reordered for the vertex cache (same triangles,
// corners possibly rotated). Decoded depths are within a relative error of
// `depth_error_relative` (> 0) of the input's (plus float rounding); pixel
// corners are exact. Deterministic. The mesh must already be valid (indices in
// range, finite values). `zstd_level` (clamped by zstd to its range) trades
// encode time for bytes; it never changes the decoded mesh.
std::optional<std::vector<std::uint8_t>> encode_grid_face_mesh(const FaceMesh& mesh, int face, int face_size,
                                                               double depth_error_relative, int zstd_level);

// Decodes a version-2 blob; positions are recomputed on their pixel rays
// exactly as build_depth_meshes computes them, so faces sharing a border
// corner with the same coded depth get bit-identical vertices. Throws
// std::runtime_error("face mesh blob: ...") on anything malformed; memory is
// bounded by a small multiple of `size`.
FaceMesh decode_grid_face_mesh(const std::uint8_t* data, std::size_t size);

}  // namespace cellbake
