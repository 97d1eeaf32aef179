// The automatic camera path of `cellbake walk --auto`: through every given
// cell in a serpentine order (floor by floor, row by row, every other row
// reversed) at eye height (the centre of each cell's navigable part), as a
// centripetal Catmull-Rom spline (Yuksel, Schaefer and Keyser, "Parameter-
// ization and applications of Catmull-Rom curves", CAD 2011: no cusps or
// self-intersections within a segment) walked at constant speed, looking
// ahead along the path so that turns are smooth. A single cell gets a loop
// around its centre. Pure code: no files, no GL.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/geometry.h"
#include "viewer/camera_path.h"

namespace cellbake {

struct WalkCell {
  std::int64_t id = 0;
  int gx = 0, gy = 0, gz = 0;  // grid place (viewer/cell_index.h CellEntry)
  Box3d bounds;                // the cell
  Box3d navigable;             // where an eye may be: the cell within its region (its bounds when empty)
};

struct AutoWalkParams {
  double speed = 1.4;       // model units (metres) per second: walking speed
  double fps = 24;          // frames per second of walk time
  double seconds = 0;       // at most this long (0: the whole path)
  double look_ahead = 2.0;  // model units: the eye looks towards the path this far ahead
};

// The cells in walking order: by floor (the grid index along `up`), then by
// row, each row along the remaining axis, every other row of a floor
// reversed. `up` is unit +z (rows along y) or +y (rows along x, columns along z).
std::vector<WalkCell> serpentine_order(std::vector<WalkCell> cells, const Vec3d& up);

// A point on the centripetal Catmull-Rom spline through `points` (at least
// 2, consecutive points distinct) at parameter u in [0, points.size() - 1]:
// u = i is points[i]. The ends are extended by reflection. Throws
// std::invalid_argument for fewer than 2 points.
Vec3d catmull_rom_point(const std::vector<Vec3d>& points, double u);

// The views of an automatic walk through `cells` (taken in serpentine_order)
// with `up` the world's up axis: one view per frame, frame k at walk time k /
// fps, eyes spaced speed / fps apart along the spline (arc length), each
// looking horizontally along the path `look_ahead` ahead (the direction to
// three points at 0.5, 1 and 1.5 times it, averaged; held at the end). The
// walk lasts the whole path, or `seconds` when that is shorter. One cell:
// a loop of radius a quarter of its smaller horizontal side around its
// centre. Deterministic. Throws std::invalid_argument when `cells` is empty
// or a parameter is not positive (seconds: negative).
std::vector<PathView> auto_walk_path(const std::vector<WalkCell>& cells, const Vec3d& up,
                                     const AutoWalkParams& params);

}  // namespace cellbake
