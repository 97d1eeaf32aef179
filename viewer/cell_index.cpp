#include "viewer/cell_index.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cellbake {

CellIndex::CellIndex(const CellDb& db) {
  for (std::int64_t id : db.cell_ids()) {
    CellEntry e;
    e.id = id;
    try {
      const auto row = db.get_cell(id, false);
      if (!row) continue;
      e.gx = row->gx, e.gy = row->gy, e.gz = row->gz;
      e.bounds = row->bounds;
      e.done = row->status == "done";
      e.cull_half_size = row->cull_half_size;
      e.near_triangles = row->near_triangles;
      e.far_triangles = row->far_triangles;
    } catch (const std::exception&) {
      continue;  // an unreadable row has no usable bounds: the eye falls back to ground truth there
    }
    cells_.push_back(e);
  }
  std::sort(cells_.begin(), cells_.end(), [](const CellEntry& a, const CellEntry& b) { return a.id < b.id; });
}

CellIndex::CellIndex(std::vector<CellEntry> cells) : cells_(std::move(cells)) {
  std::sort(cells_.begin(), cells_.end(), [](const CellEntry& a, const CellEntry& b) { return a.id < b.id; });
}

double distance_to_box(const Vec3d& p, const Box3d& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({b.lo[k] - p[k], 0.0, p[k] - b.hi[k]});
    s += d * d;
  }
  return std::sqrt(s);
}

const CellEntry* CellIndex::containing(const Vec3d& p) const {
  for (const CellEntry& c : cells_)
    if (p.x >= c.bounds.lo.x && p.x <= c.bounds.hi.x && p.y >= c.bounds.lo.y && p.y <= c.bounds.hi.y &&
        p.z >= c.bounds.lo.z && p.z <= c.bounds.hi.z)
      return &c;
  return nullptr;
}

const CellEntry* CellIndex::nearest(const Vec3d& p) const {
  if (const CellEntry* c = containing(p)) return c;
  const CellEntry* best = nullptr;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const CellEntry& c : cells_) {
    const double d = distance_to_box(p, c.bounds);
    if (d < best_distance) best_distance = d, best = &c;
  }
  return best;
}

const CellEntry* CellIndex::find(std::int64_t id) const {
  auto it = std::lower_bound(cells_.begin(), cells_.end(), id, [](const CellEntry& c, std::int64_t v) { return c.id < v; });
  return it != cells_.end() && it->id == id ? &*it : nullptr;
}

Box3d CellIndex::bounds() const {
  Box3d b;
  for (const CellEntry& c : cells_) b.expand(c.bounds);
  return b;
}

}  // namespace cellbake
