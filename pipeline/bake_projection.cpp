#include "pipeline/bake_projection.h"

#include <cmath>
#include <stdexcept>

namespace cellbake {
namespace {

std::uint64_t ceil_div(std::uint64_t a, std::uint64_t b) { return (a + b - 1) / b; }

}  // namespace

BakeProjection project_bake(const MeasuredCost& measured, std::uint64_t cells, int threads,
                            const std::vector<int>& shard_counts, int threads_per_shard) {
  if (measured.cells == 0) throw std::invalid_argument("project_bake: no measured cells");
  if (!(measured.cpu_seconds >= 0) || !std::isfinite(measured.cpu_seconds) || !(measured.bytes >= 0) ||
      !std::isfinite(measured.bytes))
    throw std::invalid_argument("project_bake: measured figures must be finite and non-negative");
  if (threads < 1 || threads_per_shard < 1) throw std::invalid_argument("project_bake: threads must be >= 1");
  BakeProjection p;
  p.cells = cells;
  p.threads = threads;
  p.cpu_seconds_per_cell = measured.cpu_seconds / double(measured.cells);
  p.bytes_per_cell = measured.bytes / double(measured.cells);
  p.cpu_seconds = p.cpu_seconds_per_cell * double(cells);
  p.bytes = p.bytes_per_cell * double(cells);
  p.wall_seconds = double(ceil_div(cells, std::uint64_t(threads))) * p.cpu_seconds_per_cell;
  for (int s : shard_counts) {
    if (s < 1) throw std::invalid_argument("project_bake: shard counts must be >= 1");
    ShardProjection sp;
    sp.shards = s;
    sp.threads_per_shard = threads_per_shard;
    sp.cells_per_shard = ceil_div(cells, std::uint64_t(s));
    sp.wall_seconds = double(ceil_div(sp.cells_per_shard, std::uint64_t(threads_per_shard))) * p.cpu_seconds_per_cell;
    p.shards.push_back(sp);
  }
  return p;
}

}  // namespace cellbake
