// Stage `cull_box`: the largest cube centred on a cell whose near field stays
// within a triangle budget (Wilson 2002, §1.6.1 and §7.3.1.2; Aliaga et al.
// 1999). A triangle belongs to the near field when it intersects the closed
// cube (Akenine-Möller 2001 overlap, see stages/triangle_box_overlap.h).
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

struct CullBoxParams {
  std::uint64_t triangle_budget = 100000;  // most triangles the near field may hold (thesis: 100,000)
  double min_half_size = 0.5;              // metres; the cell's own half extent (thesis: 1 m cells)
  // Metres; an upper cap. The model extent caps it anyway: beyond the
  // Chebyshev distance from the centre to the farthest model-bounds corner the
  // cube holds everything, so +infinity means "the model extent".
  double max_half_size = std::numeric_limits<double>::infinity();
};

// One chunk of the near field: how many of its triangles intersect the cube.
struct NearChunk {
  std::int64_t chunk_id = 0;
  std::uint32_t triangles = 0;  // > 0
  bool whole = false;           // every triangle of the chunk intersects the cube
  friend bool operator==(const NearChunk&, const NearChunk&) = default;
};

struct CullBoxResult {
  double half_size = 0;                 // metres; the cube is [centre - half_size, centre + half_size]^3
  std::uint64_t triangle_count = 0;     // exact number of triangles intersecting the cube
  std::vector<NearChunk> near_field;    // chunks with at least one intersecting triangle, sorted by id
  std::uint64_t chunks_loaded = 0;      // ChunkSource::load calls made
  std::uint64_t chunks_queried = 0;     // distinct chunks returned by ChunkSource::query
  bool budget_exceeded_at_min = false;  // even min_half_size holds more than the budget
};

// The largest half size h in [min_half_size, H] whose closed cube intersects at
// most `triangle_budget` triangles, where H = min(max_half_size, model extent)
// (H = min_half_size for an empty model). When even min_half_size holds more,
// returns min_half_size with budget_exceeded_at_min = true.
//
// Exact, not an approximate bisection: the count at h is the number of
// triangles whose Chebyshev distance d to the centre is <= h, a right-continuous
// step function, so the admissible h form [0, d*) where d* is the (budget+1)-th
// smallest d. The supremum d* itself is not admissible (the closed cube touches
// that triangle), so the result is d* minus a safety gap of 256 ulps of
// (|centre|_inf + d*) (about 5.7e-14 relative: the triangle at d* stays outside
// under any other stage's rounding of the same test), clamped to
// [min_half_size, H]. `triangle_count` and
// `near_field` are then evaluated exactly at the returned half size.
//
// Loads only the chunks whose distance interval straddles the shrinking bracket
// around d* (plus those straddling the final half size). Throws
// std::invalid_argument for bad parameters or a non-finite centre, and
// propagates ChunkSource errors; throws std::runtime_error naming the chunk
// when a loaded chunk disagrees with its index entry. Deterministic for a
// deterministic source.
CullBoxResult find_cull_box(const Vec3d& cell_center, const CullBoxParams& params, const ChunkSource& source);

// The near field of the cube of `half_size` (>= 0, finite) around
// `cell_center`, evaluated as find_cull_box evaluates it at the half size it
// chose: `triangle_count` and `near_field` (half_size = the given one). What
// a stored cell's near list must equal (`status --check`, merge). Throws as
// find_cull_box.
CullBoxResult near_field_at(const Vec3d& cell_center, double half_size, const ChunkSource& source);

}  // namespace cellbake
