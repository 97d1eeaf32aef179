// Up axis from the geometry: which of y and z is up in a model whose file
// format does not say (OBJ, PLY, OFF, STL), or a check of what it says.
// Buildings, plants and cities are dominated by a few large horizontal planes
// at a few heights (floors, ceilings, slabs, roofs, the ground); walls face
// the two other axes and spread over many positions. Every triangle whose
// normal lies within ~10 degrees of an axis adds its area to that axis' bin
// at its centroid's coordinate (one bin size for all three axes); an axis'
// plane score is the area-weighted chance that two points of the whole
// surface lie on one plane facing it:
//     score(a) = sum_i h_a[i] * (h_a[i-1] + h_a[i] + h_a[i+1]) / total_area^2
// (neighbour bins count: a plane straddling a bin edge stays one plane).
// The up axis is the candidate (y or z) whose score is both large enough and
// `min_ratio` times that of each other axis; x is always a horizontal axis
// under either candidate, so it stands for what a wall axis scores. Small
// curved objects (a duck, an engine) rarely pass: the answer is then "unsure".
// Terrain (issue #38 item 5: hills, trees, a village) has few flat planes but
// most of its area facing up: when the planes are not conclusive, the
// candidate whose facing fraction (the share of the whole area whose normal
// lies within 45 degrees of the axis, either sign) reaches
// `min_facing_fraction` and is `min_ratio` times each other axis' is the up
// axis. A cube (1/3 each) or a sphere (0.29 each) stays unsure.
// Deterministic for the same triangles added in the same order.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/geometry.h"

namespace cellbake {

struct UpAxisParams {
  double plane_cos = 0.985;  // a triangle faces an axis when |unit normal . axis| >= this (~10 degrees)
  int bins = 8192;           // bins along the model's longest side; the other axes use the same bin size
  double min_score = 0.004;  // the winner's plane score must reach this (0.018 on the generated plant)
  double min_ratio = 2.0;    // ... and be this many times the score of each other axis
  double facing_cos = 0.7071;          // terrain: a triangle faces an axis when |unit normal . axis| >= this (45 degrees)
  double min_facing_fraction = 0.5;    // terrain: the candidate's facing fraction must reach this (and min_ratio)
};

struct UpAxisGuess {
  std::string axis;  // "z", "y", or "" when unsure
  double ratio = 0;  // the best candidate's score over the best other axis' (0: no planes)
  std::array<double, 3> score{0, 0, 0};  // plane score per axis x, y, z (0..1)
  std::array<double, 3> facing{0, 0, 0};  // share of the area facing each axis within 45 degrees (0..1)
  bool from_facing = false;               // the answer came from the facing fractions (terrain), not the planes
  // One line for people: what was measured and why this answer, e.g.
  // "large flat surfaces face z (plane score z 0.018, y 0.006, x 0.003)".
  std::string evidence;
};

// Accumulates the evidence triangle by triangle (ingest feeds the chunks it
// writes; up_axis_from_geometry reads a ChunkSource).
class UpAxisEvidence {
 public:
  // `bounds` holds every triangle that will be added (the model's bounds): it
  // fixes the bins. An empty or point-like box gives "unsure".
  explicit UpAxisEvidence(const Box3d& bounds, const UpAxisParams& params = {});
  void add_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c);
  void add_chunk(const Chunk& chunk);
  // The answer for everything added so far.
  UpAxisGuess guess() const;

 private:
  UpAxisParams params_;
  Box3d bounds_;
  double bin_size_ = 0;  // 0: no bins (degenerate bounds)
  double total_area_ = 0;
  std::array<std::vector<double>, 3> area_;  // per axis: facing area per bin
  std::array<double, 3> facing_area_{0, 0, 0};  // per axis: area within 45 degrees of it
};

// The evidence over every chunk of `source` (read once, in id order).
// Throws what ChunkSource::load throws.
UpAxisGuess up_axis_from_geometry(const ChunkSource& source, const UpAxisParams& params = {});

}  // namespace cellbake
