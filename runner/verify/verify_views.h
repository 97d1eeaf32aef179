// Where `cellbake verify` looks from inside a view cell: views at uniformly
// random points of the cell's navigable part looking along uniformly random
// horizontal directions (the headline: what a person walking anywhere in the
// cell sees), and reference views at its centre and corners, reported apart
// (as are the views from the cell's sample points, which the runner adds).
// Pure code.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

// `random` views form the report's headline; `centre`, `corner` and `sample`
// (at a cell's panoramic sample points, added by the runner) are reference
// views that coincide with, or sit where the bake chose, sample points.
enum class VerifyViewKind { random, centre, corner, sample };

// "random" | "centre" | "corner" | "sample", and back (throws std::invalid_argument).
const char* view_kind_name(VerifyViewKind kind);
VerifyViewKind parse_view_kind(const std::string& name);

// Whether views of this kind form the headline (the random ones).
inline bool is_headline_view(VerifyViewKind kind) { return kind == VerifyViewKind::random; }

struct VerifyViewPlan {
  VerifyViewKind kind = VerifyViewKind::centre;
  Vec3d eye, look;  // world coordinates; look - eye is horizontal (perpendicular to up)
};

// The views of one cell: first `random_views` (>= 1) eyes drawn uniformly from
// the box `navigable` (the cell's bounds intersected with its region,
// stages/sample/sample_points.h navigable_part; a part that is flat along an axis
// gives eyes on that plane), each looking along a yaw drawn uniformly from
// [0, 2 pi) around `up`; then, when `reference_views`, the centre of
// `navigable` and its distinct corners (4 of a flat rectangle, 8 of a box),
// the corners pulled 1 % of the cell size toward the centre, looking along
// yaw = k * 137.5 degrees (the golden angle) for the k-th view overall. Every
// look point is one cell size (the largest extent of `cell`) from its eye.
// `up` must be a coordinate axis (0,0,1), (0,1,0) or (1,0,0). Deterministic
// for the same arguments (a portable generator seeded with `seed`). Throws
// std::invalid_argument for random_views < 1, an empty or non-finite box or
// another up vector.
std::vector<VerifyViewPlan> plan_verify_views(const Box3d& cell, const Box3d& navigable, const Vec3d& up,
                                              int random_views, bool reference_views, std::uint64_t seed);

// The yaw direction of reference view k (golden angle) around `up`, horizontal and unit length.
Vec3d golden_angle_direction(int k, const Vec3d& up);

}  // namespace cellbake
