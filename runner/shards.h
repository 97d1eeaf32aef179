// Shard assignment for distributed bakes: a deterministic, cost-balanced split
// of the cells into N shards (greedy longest-processing-time on an estimated
// per-cell cost), so every array task gets a similar amount of work.
#pragma once

#include <vector>

#include "pipeline/cell_grid.h"
#include "stages/chunk_source.h"

namespace cellbake {

// Estimated cost of a cell: triangles in chunks near it (a 4-cell-radius box)
// plus a constant per cell for the sampling and meshing that every cell pays.
double estimate_cell_cost(const CellSpec& cell, const ChunkSource& source);

// The cells of shard `index` (0-based) out of `count`, in id order. Every cell
// lands in exactly one shard; the split depends only on the cells and source.
std::vector<CellSpec> shard_cells(const std::vector<CellSpec>& cells, int index, int count,
                                  const ChunkSource& source);

}  // namespace cellbake
