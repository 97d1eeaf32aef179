// Compact, validated blob encoding of one chunk's geometry: float32 positions
// relative to the chunk origin + RGBA8 (+ optional uv), compressed with
// meshoptimizer's vertex and index codecs, plus per-triangle material ids and
// optional per-vertex normals (octahedral 2 x int16, stages/normal_packing.h,
// through the vertex codec).
#pragma once

#include <cstdint>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

// Encodes positions, colours, uvs, indices and materials of `chunk` (not its id,
// origin or bounds, which live in table columns). Deterministic bytes.
std::vector<std::uint8_t> encode_chunk_blob(const Chunk& chunk);

// Decodes a blob into `chunk` (positions, colours, uvs, indices, materials).
// Safe on untrusted bytes: every length, count and index is validated; throws
// std::runtime_error("chunk blob: ...") on anything malformed.
void decode_chunk_blob(const std::uint8_t* data, std::size_t size, Chunk& chunk);

}  // namespace cellbake
