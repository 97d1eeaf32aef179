// What a cube face saw, triangle by triangle (CubeFace::seen): from the chunk
// and triangle that drew each pixel of a face rendering to the SeenChunk list
// the far choice reads (stages/far/far_choice.h). Shared by the sampling backends
// that know their pixels' triangles (the Embree ray caster's hits, the GL
// rasteriser's primitive-id attachment), so both report alike: chunks by id,
// triangles ascending, each with the tiles (pixel_tile of the rendered pixel,
// at the supersampled resolution) it drew in.
#pragma once

#include <cstdint>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

#include "stages/cube_map.h"

namespace cellbake {

// The far-field tile (pixel_tile) of each pixel of a size x size face,
// row-major, row 0 at the top. Throws std::invalid_argument for size < 1.
std::vector<std::uint32_t> pixel_tiles(int size);

// Reused buffers of seen_triangles(); one per thread.
struct SeenScratch {
  struct Range {
    std::uint32_t lo, hi;    // of the chunk's triangles seen
    std::size_t offset = 0;  // of its masks in `masks`
  };
  std::unordered_map<std::int64_t, Range> ranges;
  std::vector<std::pair<std::int64_t, Range*>> by_id;
  std::vector<std::uint16_t> masks;  // per triangle in each range: tiles it drew in
};

// What a face saw, sorted by chunk id: per chunk, the triangles that drew a
// pixel (ascending) with the tiles they drew in. `chunk[p]` is the id of the
// chunk that drew pixel p (negative: none), `triangle[p]` its triangle number
// (the index into the chunk's `indices` / 3), `tile[p]` the pixel's tile
// (pixel_tiles). Only the span of triangle numbers a chunk drew is cleared
// and scanned (a face sees most chunks only in part), and neighbouring pixels
// mostly share a chunk, so the chunk lookups are few. Throws
// std::invalid_argument when the three spans differ in length or a tile is
// not below kFarTilesPerFace.
std::vector<SeenChunk> seen_triangles(std::span<const std::int64_t> chunk,
                                      std::span<const std::uint32_t> triangle,
                                      std::span<const std::uint32_t> tile, SeenScratch& scratch);

}  // namespace cellbake
