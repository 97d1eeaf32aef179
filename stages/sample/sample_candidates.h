// Candidate positions for the next panoramic sample: Voronoi best-next-view
// (Wilson 2002, ch. 3, §3.4.2.5 and Figure 3.25). New samples go where the void
// surface is expected to be most visible, i.e. as far from every existing
// sample as possible: at the vertices of the Voronoi diagram of the sample
// positions inside the navigable region, and where its edges cross the
// region's boundary. The navigable region is a 2D rectangle (the thesis' user
// moves in a plane); stages/sample/sample_void.h scores the candidates.
#pragma once

#include <span>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct Vec2d {
  double x = 0, y = 0;
  friend bool operator==(const Vec2d&, const Vec2d&) = default;
};

// A closed rectangle, lo <= hi per axis. It may be degenerate: a segment
// (lo.x == hi.x or lo.y == hi.y) or a point (lo == hi).
struct Rect2d {
  Vec2d lo, hi;
  friend bool operator==(const Rect2d&, const Rect2d&) = default;
};

// Candidate positions for the next sample: the vertices of the Voronoi diagram
// of `samples` that lie in `rect` (closed), plus the points where Voronoi edges
// (segments, rays or full lines) meet the boundary of `rect`. Built on CGAL's
// Delaunay_triangulation_2 with exact predicates (Voronoi vertices and edges
// are its duals; the constructions are in double).
//
// With eps = 1e-9 * (diagonal of rect + 1), in model units:
//  * 0 samples: the centre of rect.
//  * samples closer than eps to an earlier kept one (in x-then-y order) are
//    duplicates and count once.
//  * 1 distinct sample (no Voronoi edges): the corners of rect.
//  * all samples collinear (CGAL's dimension 1): the perpendicular bisectors
//    of consecutive samples met with the boundary; there are no vertices.
//  * a point within eps outside rect counts as inside and is clamped onto it.
//  * a Voronoi edge running along a side of rect contributes the ends of their
//    overlap (Voronoi vertices or corners), not the segment.
//  * a segment rect: Voronoi vertices on it, its crossings with Voronoi edges,
//    and its two end points. A point rect: that point.
//  * candidates closer than eps to a sample are dropped, and of candidates
//    closer than eps to each other the first in x-then-y order is kept.
// Returns the candidates sorted by x, then y, without duplicates; possibly
// empty (a point rect on a sample). The result depends on the set of samples
// only, not on their order (they are sorted before insertion), bit for bit.
// Throws std::invalid_argument for non-finite coordinates or rect.lo > rect.hi.
std::vector<Vec2d> voronoi_candidates(const std::vector<Vec2d>& samples, const Rect2d& rect);

// The points a cell's best-next-view search scores next, given its navigable
// part `nav` and the eyes sampled so far: when `nav` is flat along an axis
// (extent <= 1e-9 * (sum of extents + 1); the first such axis from x), the
// voronoi_candidates of the eyes in the plane of the other two axes (in
// axis order), each at nav's centre along the flat one; else the 27 lattice
// points of the box (corners, edge and face midpoints, centre; x fastest)
// that are not exactly an eye. Deterministic; throws as voronoi_candidates.
std::vector<Vec3d> next_view_candidates(const Box3d& nav, std::span<const Vec3d> eyes);

}  // namespace cellbake
