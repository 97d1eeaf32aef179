// Simplification of dense per-face depth meshes into small textured-depth-mesh
// geometry, with a guaranteed depth error and unchanged screen coverage.
//
// Wilson 2002, ch. 5 §5.2.3 (view-dependent error: boundaries and silhouettes
// may move at most half a pixel in screen space, interior points have latitude
// along the view direction; the faces of a cube must meet without cracks).
// Instead of the thesis' GAPS / Garland-Heckbert edge collapses we exploit the
// grid: outlines are straightened as staircases in pixel space, and the
// interior is a constrained Delaunay triangulation refined by greedy insertion
// (Garland & Heckbert 1995) in (x, y, 1/z) screen space, where a world-space
// plane is an exact plane. See simplify.cpp for the steps.
#pragma once

#include <cstddef>
#include <memory>

#include "stages/cube_map.h"
#include "stages/simplify/simplify_error.h"

namespace cellbake {

struct SimplifyParams {
  // Max relative depth error |z_out - z_in| / z_in at the dense mesh's vertices
  // away from outlines, measured along the eye ray (output vertices are input
  // vertices: they never move across the view direction).
  double depth_error_relative = 0.01;
  // Max screen-space displacement, in pixels, of silhouettes, skins and
  // coverage edges (the outlines of the dense mesh inside the face). 0 keeps
  // them pixel-exact (staircases). Face borders never move.
  double boundary_error_px = 0.5;
  // Per-face triangle cap (VWALK used 10,000). Refinement inserts the worst
  // violation first; once the mesh reaches the cap it stops as soon as no
  // violation exceeds depth_error_relative * max_depth_error_factor (it goes on
  // past the cap until then, e.g. when the outlines alone need more
  // triangles than the cap). Outlines and face borders always use
  // depth_error_relative, so neighbouring faces still agree.
  std::size_t max_triangles = 10000;
  double max_depth_error_factor = 8;
  // Measure SimplifyResult::achieved (about a third of the time). A caller
  // that keeps only some meshes measures those it keeps later, with a
  // SimplifyRuler or measure_simplification_error (the same figures).
  bool measure_error = true;
};

struct SimplifyResult {
  FaceMesh mesh;  // vertices are a subset of the input's (bit-identical positions and uvs)
  std::size_t triangles_in = 0;
  std::size_t triangles_out = 0;
  // Triangles of the outline-only triangulation refinement starts from (the
  // outlines and face borders alone): a lower bound on triangles_out (the
  // refinement only adds triangles), known before the refinement runs.
  std::size_t outline_triangles = 0;
  double depth_error_bound_used = 0;    // interior bound of the final mesh (> params' when the cap stopped refinement)
  bool cap_forced_larger_error = false;  // the cap made us exceed depth_error_relative
  SimplifyError achieved;                // measured against the input (zero unless params.measure_error)
};

// Simplifies one dense face mesh from build_depth_meshes (a pixel grid with
// face_size^2 pixels). Guarantees, by construction and checked by the measured
// `achieved`: outlines (silhouettes, skins, coverage edges) move at most
// boundary_error_px in screen space and the two sides of one outline share the
// same screen-space line (no gaps, no overlaps), face borders do not move, no
// triangle flips in screen space, depth error <= depth_error_bound_used at the
// input vertices not on an outline (those on one keep their exact depth). Face
// borders are simplified by a rule that reads only border data that
// neighbouring faces share bit for bit, so the six faces of a sample keep
// identical border vertices (no cracks) when all are simplified with the same
// params. Deterministic. The cap may be unreachable for faces dominated by
// outlines (then triangles_out > max_triangles). Throws std::invalid_argument
// when `in` is not a pixel-grid mesh of that size.
SimplifyResult simplify_face_mesh(const FaceMesh& in, int face_size, const SimplifyParams& params);

struct DenseFaceAnalysis;

// What measuring a simplified face needs of the dense mesh it came from (its
// vertices, grid, regions and outlines: ~15 MB for a 512^2 face), kept by
// FaceSimplification::finish(ruler) so that a caller can measure later only
// the meshes it keeps, without analysing their dense meshes again.
class SimplifyRuler {
 public:
  SimplifyRuler();
  ~SimplifyRuler();
  SimplifyRuler(SimplifyRuler&&) noexcept;
  SimplifyRuler& operator=(SimplifyRuler&&) noexcept;

  // Whether it holds a dense mesh's analysis.
  explicit operator bool() const { return dense_ != nullptr; }
  // SimplifyResult::achieved for `simplified`, the mesh finish(ruler)
  // returned: the figures measure_simplification_error gives against the
  // dense mesh. Throws std::logic_error when it holds none.
  SimplifyError measure(const FaceMesh& simplified) const;

 private:
  friend class FaceSimplification;
  std::unique_ptr<DenseFaceAnalysis> dense_;
};

// simplify_face_mesh in two steps, for a caller that may not need the mesh:
// constructing reads the grid, straightens the outlines and triangulates them
// (about two thirds of the work), after which outline_triangles() is a lower
// bound on the result's triangles; finish() refines and returns exactly what
// simplify_face_mesh returns. Holds the dense mesh's analysis (tens of MB for
// a 512^2 face) until finished or destroyed. Throws as simplify_face_mesh.
class FaceSimplification {
 public:
  // `in` must outlive this object.
  FaceSimplification(const FaceMesh& in, int face_size, const SimplifyParams& params);
  // Keeps `in`.
  FaceSimplification(FaceMesh&& in, int face_size, const SimplifyParams& params);
  ~FaceSimplification();
  FaceSimplification(FaceSimplification&&) noexcept;
  FaceSimplification& operator=(FaceSimplification&&) noexcept;

  // SimplifyResult::outline_triangles of the result, known without refining.
  std::size_t outline_triangles() const;
  // Refines; callable once (throws std::logic_error after that).
  SimplifyResult finish() &&;
  // The same, without measuring (achieved stays zero, whatever
  // params.measure_error says); `ruler` takes the dense mesh's analysis to
  // measure the result later. A borrowed input must outlive the ruler.
  SimplifyResult finish(SimplifyRuler& ruler) &&;

 private:
  struct State;
  void start(int face_size, const SimplifyParams& params);
  std::unique_ptr<State> state_;
  std::size_t outline_triangles_ = 0;
};

}  // namespace cellbake
