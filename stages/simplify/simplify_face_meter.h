// A triangle of the simplifier's triangulation (simplify.cpp) read against
// the dense face mesh: the dense vertex it takes at each corner, and how far
// its plane in (x, y, 1/z) screen space misses its region's dense vertices
// (greedy insertion, Garland & Heckbert 1995, "Fast polygonal approximation
// of terrains and height fields"; view-dependent error: Wilson 2002, ch. 5
// §5.2.3).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "stages/simplify/simplify_cdt.h"
#include "stages/simplify/simplify_grid.h"
#include "stages/simplify/simplify_outline.h"

namespace cellbake {

// The worst violations of one triangle: the worst dense vertex off its
// constrained edges (to insert), and the worst on a straightened outline
// segment among its edges (to refine that segment). Errors are relative
// depth errors; 0 when there is no violation of that kind.
struct FaceViolation {
  double free_error = 0, bound_error = 0;
  LatticePoint free_at{-1, -1};
  ConstraintOwner bound_owner;
  double worst() const { return std::max(free_error, bound_error); }
};

// Reads the labelled faces of `cdt` (whose constraints `owners` owns) against
// the dense face `g` with regions `regions` and outlines `outlines`. All are
// referred to and must outlive the meter; which lattice points lie off the
// outlines is indexed once, on construction (refining outlines keeps them).
class TinFaceMeter {
 public:
  // `eps`: the relative depth error a dense vertex may have.
  TinFaceMeter(const FaceGrid& g, const FaceRegions& regions, const FaceOutlines& outlines,
               const ConstraintOwners& owners, const Cdt& cdt, double eps);

  // The lattice points `p` of face f's corners and the dense vertices `v` the
  // face takes there (its region's vertex there, on the face's side where
  // the region meets itself); false when some corner has none.
  bool corners(const Cdt::Face_handle& f, std::array<LatticePoint, 3>& p, std::array<std::uint32_t, 3>& v) const;
  // The worst violations of face f beyond eps (see FaceViolation); none for
  // background or a degenerate face.
  FaceViolation evaluate(const Cdt::Face_handle& f) const;

 private:
  std::size_t lattice_index(int x, int y) const { return cellbake::lattice_index(x, y, n_); }
  int label(int i, int j) const { return regions_.label[std::size_t(j) * n_ + i]; }
  // Lattice points off every outline: all pixels around one share a region
  // and a vertex (or none is covered), so their vertex needs no search.
  void index_interior_lattice(const FaceOutlines& outlines);
  // Dense vertex of region l at lattice point p for a triangle whose centroid is (cx, cy).
  std::uint32_t pick_vertex(int l, LatticePoint p, double cx, double cy) const;
  // Dense vertex of corner k of face f where the region meets itself at that
  // point with several vertices (the end of a skin, a pinch): the constraint
  // met first turning counter-clockwise about the corner starts with an
  // outline step d; the face lies on its clockwise side, in the pixel there.
  std::uint32_t pick_corner_vertex(Cdt::Face_handle f, int k, double cx, double cy) const;
  // The edge of face f (corners p) that is constrained and whose line holds
  // lattice point q, or -1.
  int constrained_edge_through(const Cdt::Face_handle& f, const std::array<LatticePoint, 3>& p, LatticePoint q) const;
  // True when the pixels of region l around lattice point p share one vertex there.
  bool unique_vertex(int l, LatticePoint p) const;

  const FaceGrid& g_;
  const FaceRegions& regions_;
  const FaceOutlines& outlines_;
  const ConstraintOwners& owners_;
  const Cdt& cdt_;
  int n_;
  double eps_;
  std::vector<std::int32_t> interior_region_;  // per lattice point off the outlines: its region, or -1
  std::vector<double> interior_w_;             // and the inverse depth of its vertex
};

}  // namespace cellbake
