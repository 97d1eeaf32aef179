// View cells: cubes of side `cell_size` tiling each region from its minimum
// corner (a region thinner than a cell on some axis gives one layer there).
// Ids are 1, 2, 3 ... in region order, then z, y, x: deterministic for a config.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct CellSpec {
  std::int64_t id = 0;
  int region = 0;
  int gx = 0, gy = 0, gz = 0;
  Box3d bounds;
  Vec3d center() const { return bounds.center(); }
  double half_size() const { return 0.5 * (bounds.hi.x - bounds.lo.x); }
};

// Enumerates every cell of every region. Throws std::invalid_argument when the
// cell size is not positive or the cell count would exceed `max_cells`.
std::vector<CellSpec> enumerate_cells(const std::vector<Box3d>& regions, double cell_size,
                                      std::uint64_t max_cells = 50'000'000);

// Refuses useless bakes: throws std::invalid_argument naming the region
// (1-based, with its corners) and the model bounds when a region does not meet
// `model_bounds` grown by one `cell_size` on every side (its cells would see
// nothing nearby). An empty model (empty bounds) passes: nothing to compare.
void check_regions_meet_model(const std::vector<Box3d>& regions, const Box3d& model_bounds, double cell_size);

// The cell `id` of enumerate_cells(regions, cell_size) without enumerating
// the others (region, grid indices and bounds computed alike), or nullopt
// when the regions hold fewer cells. Throws as enumerate_cells for a bad cell
// size or region.
std::optional<CellSpec> cell_of_id(const std::vector<Box3d>& regions, double cell_size, std::int64_t id);

// How many cells enumerate_cells(regions, cell_size) gives; throws alike.
std::uint64_t count_cells(const std::vector<Box3d>& regions, double cell_size);

// Parses a cell selection like "1-10,15,20-" (ranges inclusive, open end = to the
// last id) and keeps only the cells it names. Throws std::invalid_argument on bad
// syntax and when a non-empty selection names none of a non-empty `cells`.
std::vector<CellSpec> select_cells(const std::vector<CellSpec>& cells, const std::string& selection);

}  // namespace cellbake
