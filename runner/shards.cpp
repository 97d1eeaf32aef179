#include "runner/shards.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace cellbake {

double estimate_cell_cost(const CellSpec& cell, const ChunkSource& source) {
  const double h = 4 * cell.half_size() * 2;
  const Box3d probe = Box3d::cube(cell.center(), h);
  double triangles = 0;
  for (const auto& c : source.query(probe)) triangles += c.triangle_count;
  return 1e5 + triangles;
}

std::vector<CellSpec> shard_cells(const std::vector<CellSpec>& cells, int index, int count,
                                  const ChunkSource& source) {
  if (count < 1 || index < 0 || index >= count)
    throw std::invalid_argument("shard " + std::to_string(index) + "/" + std::to_string(count) + " is out of range");
  std::vector<double> cost(cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i) cost[i] = estimate_cell_cost(cells[i], source);
  std::vector<std::size_t> order(cells.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return cost[a] != cost[b] ? cost[a] > cost[b] : cells[a].id < cells[b].id;
  });
  std::vector<double> load(count, 0);
  std::vector<CellSpec> out;
  for (std::size_t i : order) {
    const int target = int(std::min_element(load.begin(), load.end()) - load.begin());
    load[target] += cost[i];
    if (target == index) out.push_back(cells[i]);
  }
  std::sort(out.begin(), out.end(), [](const CellSpec& a, const CellSpec& b) { return a.id < b.id; });
  return out;
}

}  // namespace cellbake
