// The face-border rule of simplify_face_mesh: which border vertices a
// simplified face keeps, decided from data that neighbouring cube faces share
// bit for bit, so both faces keep the same vertices (no cracks).
//
// Wilson 2002, ch. 5 §5.2.3 (the faces of a cube must meet without cracks).
#pragma once

#include <vector>

#include "stages/cube_map.h"
#include "stages/simplify/simplify_grid.h"

namespace cellbake {

// A border interval [a, b] of side `side` (0: top row y = 0, 1: bottom y = N,
// 2: left x = 0, 3: right x = N; t runs along x for sides 0/1, along y for 2/3).
struct BorderPiece {
  int side = 0, a = 0, b = 0;
  bool covered = false;  // the border pixels along it are covered (then it is one output edge)
};

// Cuts each border line into intervals by a fixed, reversal-symmetric
// recursive bisection (even lengths in halves, odd as (L-1)/2, 1, (L-1)/2). An
// interval is kept whole when every lattice point inside it is clean (the two
// border pixels there share their vertices on the border and one pixel
// inside; build_depth_meshes makes this true on both neighbouring faces or on
// neither) and its inner vertices lie within `depth_error_relative` of the
// straight segment, measured along their eye rays. Needs size >= 2. Deterministic.
std::vector<BorderPiece> split_face_border(const FaceMesh& in, const FaceGrid& g, double depth_error_relative);

// Vertex of covered piece p at its coordinate t (p.a or p.b).
std::uint32_t border_piece_vertex(const FaceGrid& g, const BorderPiece& p, int t);

// Lattice point of coordinate t on `side`.
inline std::array<int, 2> border_point(int side, int t, int size) {
  switch (side) {
    case 0: return {t, 0};
    case 1: return {t, size};
    case 2: return {0, t};
    default: return {size, t};
  }
}

}  // namespace cellbake
