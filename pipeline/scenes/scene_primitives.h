// Geometric primitives for the procedural scenes: oriented boxes, surfaces of
// revolution ("lathe": columns, tanks, domes, table legs) and tubes swept along
// right-angled polylines with torus bends (pipe runs). Each primitive appends
// to a TriangleMesh with one colour, winds its triangles counter-clockwise
// seen from outside, and has an exact triangle/vertex count function that the
// scene generator uses to plan density before emitting anything.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct PrimitiveSize {
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
};

// ---- Oriented box ---------------------------------------------------------
// A box centred at `center` with half-axis vectors `half_u`, `half_v`, `half_w`
// (mutually orthogonal, non-zero; any handedness). 8 vertices, 12 triangles.
inline PrimitiveSize box_size() { return {12, 8}; }
void append_oriented_box(TriangleMesh& mesh, Vec3d center, Vec3d half_u, Vec3d half_v, Vec3d half_w,
                         Rgba8 color);
// An axis-aligned box; `box` must have positive extent on every axis.
void append_box(TriangleMesh& mesh, const Box3d& box, Rgba8 color);

// ---- Surface of revolution ------------------------------------------------
// A profile point: distance from the axis and height along it (metres).
struct LatheSample {
  double radius = 0;
  double height = 0;
};
// The profile runs from the bottom to the top of the solid (e.g. centre of the
// bottom cap -> rim -> up the side -> centre of the top); the first and last
// samples may have radius 0 (a pole), all others must be > 0, and consecutive
// samples must differ. `segments` >= 3 around the axis.
PrimitiveSize lathe_size(std::span<const LatheSample> profile, int segments);
// Revolves `profile` about the axis through `base` along unit vector `axis`.
// Throws std::invalid_argument for a profile that breaks the rules above.
void append_lathe(TriangleMesh& mesh, Vec3d base, Vec3d axis, std::span<const LatheSample> profile,
                  int segments, Rgba8 color);

// ---- Pipe along a polyline -------------------------------------------------
struct PipeStyle {
  double radius = 0.05;         // metres
  double bend_radius = 0.15;    // centre-line radius of the torus bends (clamped to fit short legs)
  int segments = 8;             // around the pipe, >= 3
  int bend_segments = 4;        // along each 90-degree bend, >= 1
  double max_piece_length = 0;  // straight legs are cut into pieces no longer than this; 0 = one piece
  bool caps = true;             // close both ends with a fan around a centre vertex
};
// The path has >= 2 points; consecutive legs are non-zero and perpendicular
// (pipes are routed at right angles). Throws std::invalid_argument otherwise,
// or when a leg is too short to hold its bends without folding the tube.
PrimitiveSize pipe_size(std::span<const Vec3d> path, const PipeStyle& style);
void append_pipe(TriangleMesh& mesh, std::span<const Vec3d> path, const PipeStyle& style, Rgba8 color);

}  // namespace cellbake
