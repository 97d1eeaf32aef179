// Which triangles of a stored chunk a cell's far field draws (issue #13),
// coded as runs: the far field's exact geometry is a part of the model the
// viewer already reads from the geometry store for the near field, so a cell
// stores only the triangle numbers, not the triangles (issue #16).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace cellbake {

// Triangle numbers above this are refused by both functions (the chunk codec's
// own limit on a chunk's triangles).
constexpr std::uint32_t kMaxTriangleListIndex = 1u << 26;

// Encodes `triangles` (strictly ascending, each < kMaxTriangleListIndex;
// std::invalid_argument otherwise; may be empty) as "CBTL", a version byte,
// the count and the runs of consecutive numbers as (gap, length) LEB128
// varints. Deterministic bytes; about one byte per run.
std::vector<std::uint8_t> encode_triangle_list(std::span<const std::uint32_t> triangles);

// True when `data` starts like an encode_triangle_list() blob (a cell's far
// geometry rows hold either this or, before schema v5 data, a chunk blob).
bool is_triangle_list_blob(std::span<const std::uint8_t> data);

// Decodes a blob of encode_triangle_list(): the ascending triangle numbers.
// Safe on untrusted bytes: throws std::runtime_error("triangle list: ...") on
// a bad magic or version, a truncated or overlong varint, runs that overlap,
// are empty, exceed the limit or disagree with the count, or trailing bytes.
std::vector<std::uint32_t> decode_triangle_list(std::span<const std::uint8_t> data);

}  // namespace cellbake
