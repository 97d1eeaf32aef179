// Where `cellbake verify` looks from inside a view cell: the centre, the
// cell's corners (kept just inside it) and seeded random interior points, each
// with a deterministic horizontal view direction. Pure code.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

// `sample` views stand at a cell's panoramic sample points (the runner adds
// them; plan_verify_views does not).
enum class VerifyViewKind { centre, corner, interior, sample };

// "centre" | "corner" | "interior" | "sample", and back (throws std::invalid_argument).
const char* view_kind_name(VerifyViewKind kind);
VerifyViewKind parse_view_kind(const std::string& name);

struct VerifyViewPlan {
  VerifyViewKind kind = VerifyViewKind::centre;
  Vec3d eye, look;  // world coordinates; look - eye is horizontal (perpendicular to up)
};

// `count` views of the cell `bounds` (count >= 1): view 0 at the centre; then
// the corners, pulled 1 % of the cell size inside it: for a `flat` cell (a
// single layer of eye height, e.g. a walkthrough) the 4 corners of the
// horizontal square through the centre, else the 8 corners of the cube;
// then interior points drawn uniformly from the cell (at the centre's height
// when flat) by a generator seeded with `seed`. View k looks horizontally along
// yaw = k * 137.5077 degrees (the golden angle; directions spread evenly)
// around `up`, at a point one cell size away. `up` must be a coordinate axis
// (0,0,1), (0,1,0) or (1,0,0). Deterministic for the same arguments. Throws
// std::invalid_argument for count < 1, an empty box or another up vector.
std::vector<VerifyViewPlan> plan_verify_views(const Box3d& bounds, bool flat, const Vec3d& up, int count,
                                              std::uint64_t seed);

// True when `region` is thinner than `cell_size` along `up` (its cells form a
// single, centred layer of eye heights).
bool region_is_flat(const Box3d& region, const Vec3d& up, double cell_size);

}  // namespace cellbake
