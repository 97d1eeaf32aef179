// Outlines of the surface regions of a dense face mesh, and their
// straightening within a screen-space tolerance (boundary straightening for
// simplify_face_mesh).
//
// Wilson 2002, ch. 5 §5.2.3: boundaries and silhouettes may move at most half
// a pixel. The dense mesh's outlines are pixel staircases; each is cut at its
// junctions into chains that are simplified once, by Douglas-Peucker (Douglas
// & Peucker 1973) on the staircase corners, so the two sides of a silhouette
// or skin get the very same straightened line (no gap, no overlap), and then
// refined until no two straightened segments cross or touch (a topology-
// preserving simplification of the planar map of regions).
#pragma once

#include <cstdint>
#include <vector>

#include "stages/simplify/simplify_grid.h"

namespace cellbake {

struct LatticePoint {
  int x = 0, y = 0;  // pixel-corner coordinates, 0..size
  friend bool operator==(const LatticePoint&, const LatticePoint&) = default;
};

// Surface regions: pixels joined across a pixel side when both share the two
// vertices of that side (no skin between them).
struct FaceRegions {
  std::vector<std::int32_t> label;  // per pixel (row-major): region id >= 0, or -1 where not covered
  int count = 0;
  // Per pixel (row-major): kJoinsEast / kJoinsSouth when it shares the
  // vertices of that side with its neighbour there (both covered).
  std::vector<std::uint8_t> joins;
  static constexpr std::uint8_t kJoinsEast = 1, kJoinsSouth = 2;
};

// Labels the regions of `g` in row-major order of their first pixel. Deterministic.
FaceRegions label_face_regions(const FaceGrid& g);

// One outline chain: a staircase of unit lattice edges between two junction
// points (or half of a closed loop), and which of its points the straightened
// chain keeps (always both ends).
struct OutlineChain {
  std::vector<LatticePoint> points;
  std::vector<std::uint8_t> kept;
  // Per point: the two sides share their vertex there (the outline is a skin
  // that closes at that point). A straightened segment between two such
  // points would join both sides along it, so straightening never makes one
  // that skips over points where they do not.
  std::vector<std::uint8_t> joined;
  // Per point: inverse planar depth of the vertex on each side of the outline
  // (left and right of the walking direction, lattice y down), 0 where that
  // side is not covered.
  std::vector<double> w_left, w_right;
};

struct FaceOutlines {
  std::vector<OutlineChain> chains;
  // Per lattice point ((size + 1)^2, row-major): 1 where an outline edge
  // (a pixel side inside the face that is a silhouette, skin or coverage edge)
  // touches the point.
  std::vector<std::uint8_t> on_outline;
  // The bounds of the last straightening (re-insertions keep them).
  double tolerance_px = 0, depth_error_relative = 0;
};

// Traces the outline edges of the face (pixel sides inside the face between
// pixels of different regions, or of one region that do not share both
// vertices) into chains. Junctions (points where the outline does not simply
// pass through) and face-border points end chains; a closed loop is cut at its
// first point in row-major order and at the point farthest from it.
// Deterministic. Every chain starts with all points kept.
FaceOutlines trace_face_outlines(const FaceGrid& g, const FaceRegions& regions);

// A segment that straightening must not cross or touch except at shared end
// points (the face-border edges the border rule keeps).
struct FixedSegment {
  LatticePoint a, b;
};

// Straightens every chain with Douglas-Peucker at `tolerance_px` (every
// dropped staircase point within tolerance_px of its straightened segment, and
// the depth of each side there within `depth_error_relative` of the depth
// interpolated in (x, y, 1/z) along the segment at its nearest point), then
// re-inserts staircase points until no two segments (chains' and fixed) cross,
// overlap or touch other than at a shared end point, and no segment joins the
// two sides of its outline at both ends. Deterministic.
void straighten_face_outlines(FaceOutlines& outlines, const std::vector<FixedSegment>& fixed, double tolerance_px,
                              double depth_error_relative, int face_size);

// A straightened segment: points [i, j] of chain `chain` (kept ends).
struct ChainSegment {
  int chain = 0, i = 0, j = 0;
};

// Re-inserts, for each segment, its inner point farthest from it, then repeats
// the non-crossing repair of straighten_face_outlines. Returns false when no
// segment had an inner point (nothing changed).
bool refine_outline_segments(FaceOutlines& outlines, const std::vector<ChainSegment>& segments,
                             const std::vector<FixedSegment>& fixed, int face_size);

}  // namespace cellbake
