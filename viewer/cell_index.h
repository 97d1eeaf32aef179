// Which view cell a viewer's eye is in: the bounds and state of every cell row
// of a cell database, read once (without blobs) and searchable by point.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/geometry.h"
#include "storage/cell_db.h"

namespace cellbake {

struct CellEntry {
  std::int64_t id = 0;
  int gx = 0, gy = 0, gz = 0;
  Box3d bounds;
  bool done = false;  // status "done" (else "failed")
  double cull_half_size = 0;
  std::uint64_t near_triangles = 0, far_triangles = 0;
};

class CellIndex {
 public:
  CellIndex() = default;
  // Reads every cell row of `db` (no blobs). Rows whose near list cannot be
  // read still get an entry (not done). Cells are kept in id order.
  explicit CellIndex(const CellDb& db);
  explicit CellIndex(std::vector<CellEntry> cells);

  // The lowest-id cell whose closed bounds contain `p`, or nullptr.
  const CellEntry* containing(const Vec3d& p) const;
  // The containing cell, else the cell whose bounds are nearest to `p`
  // (Euclidean distance to the box; ties: lowest id); nullptr when empty.
  const CellEntry* nearest(const Vec3d& p) const;
  // The cell with id `id`, or nullptr.
  const CellEntry* find(std::int64_t id) const;
  const std::vector<CellEntry>& cells() const { return cells_; }
  // Union of all cell bounds (empty box when there are no cells).
  Box3d bounds() const;

 private:
  std::vector<CellEntry> cells_;
};

// Euclidean distance from `p` to the closed box `b` (0 inside).
double distance_to_box(const Vec3d& p, const Box3d& b);

}  // namespace cellbake
