// The pixel-grid view of a dense face mesh from build_depth_meshes: for every
// pixel the vertex at each of its four corners, and for every vertex its
// lattice position (pixel-corner coordinates) and inverse planar depth. Used by
// the simplifier and by its error measurement.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "stages/cube_map.h"

namespace cellbake {

constexpr std::uint32_t kNoVertex = 0xffffffffu;

struct FaceGrid {
  int size = 0;
  std::vector<std::array<std::uint32_t, 4>> corner_vertex;  // per pixel (row-major): NW, NE, SW, SE; kNoVertex if not covered
  std::vector<std::int32_t> x, y;                           // per vertex: lattice column and row (0..size)
  std::vector<double> w;                                     // per vertex: 1 / planar depth
  int orientation = -1;  // sign of the lattice-space orientation of the input's triangles (x right, y down)

  bool covered(int i, int j) const { return corner_vertex[std::size_t(j) * size + i][0] != kNoVertex; }
  // Vertex of covered pixel (i, j) at its corner (cx, cy), which must touch the pixel.
  std::uint32_t vertex(int i, int j, int cx, int cy) const {
    return corner_vertex[std::size_t(j) * size + i][(cy - j) * 2 + (cx - i)];
  }
};

// Lattice coordinates of a vertex from its uv (uv * size, rounded).
// Inverse planar depth of a vertex: planar depth = |p| / sqrt(1 + s^2 + t^2).
double inverse_planar_depth(Vec3f p, double lattice_x, double lattice_y, int size);

// Reads a pixel-grid mesh (each covered pixel: two triangles whose corners are
// its four pixel corners, uv = corner / size). Throws std::invalid_argument
// naming the triangle or vertex when the mesh is not such a grid or a depth is
// not positive and finite.
FaceGrid read_face_grid(const FaceMesh& mesh, int face_size);

}  // namespace cellbake
