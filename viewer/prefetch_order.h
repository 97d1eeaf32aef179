// Which cells the interactive viewer loads ahead, in walking order: the eye's
// recent motion (EyeMotion) ranks the neighbours of its cell by when a straight
// walk would enter them, so the cell the walk is heading into is decoded (and
// its far field uploaded) first. Pure: no files, no GL, no threads.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "stages/geometry.h"
#include "viewer/cell_index.h"

namespace cellbake {

// The eye's positions over the last few frames and the velocity they give.
class EyeMotion {
 public:
  // Keeps the positions of the last `frames` frames (at least 2).
  explicit EyeMotion(std::size_t frames = 8);
  // Records the eye of one frame.
  void add(const Vec3d& eye);
  // Mean displacement per frame over the kept frames (zero with fewer than two).
  Vec3d velocity() const;

 private:
  std::deque<Vec3d> positions_;
  std::size_t frames_;
};

struct PrefetchOrder {
  std::vector<std::int64_t> ids;  // best first
  // The first cell a straight walk from the eye along the velocity enters
  // (0: none, e.g. a still eye or a walk out of the baked cells).
  std::int64_t heading = 0;
};

// The done cells other than `current` within `reach` of its centre (the
// viewer's neighbourhood), best first: the cells a straight walk from `eye`
// along `velocity` (per frame) enters, soonest first, then the rest by their
// distance from the eye (ties: lower id). A zero velocity ranks all by distance.
PrefetchOrder prefetch_order(const CellIndex& index, const CellEntry& current, const Vec3d& eye,
                             const Vec3d& velocity, double reach);

// When a ray from `origin` along `direction` enters the closed box `box`, in
// units of `direction` (0 when `origin` is inside); negative when it never
// does, or touches it only at `origin` while moving away.
double ray_entry(const Vec3d& origin, const Vec3d& direction, const Box3d& box);

}  // namespace cellbake
