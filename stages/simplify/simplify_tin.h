// The interior of a simplified face (simplify.cpp step 3): a constrained
// Delaunay triangulation of the straightened outlines and the kept face-border
// segments, refined by greedy insertion (Garland & Heckbert 1995, "Fast
// polygonal approximation of terrains and height fields"): every triangle
// whose plane in (x, y, 1/z) screen space misses one of its region's dense
// vertices by more than the relative depth bound is queued by its worst miss;
// the worst is inserted first, until none is left or the triangle cap is
// reached with every miss within the cap's looser bound. A violation on a
// straightened outline segment re-inserts that segment's farthest staircase
// point instead (all such segments at once, then the triangulation is
// rebuilt). View-dependent error: Wilson 2002, ch. 5 §5.2.3.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "stages/simplify/simplify_cdt.h"
#include "stages/simplify/simplify_face_meter.h"
#include "stages/simplify/simplify_grid.h"
#include "stages/simplify/simplify_outline.h"
#include "stages/simplify/simplify_queue.h"

namespace cellbake {

class TinSimplifier {
 public:
  // The dense face `g` with regions `regions` (both must outlive the
  // simplifier), straightened `outlines` and the border segments `fixed`
  // (must outlive it too); `eps` the relative depth bound. `cap` and
  // `ceiling`: once the mesh has at least `cap` triangles, refinement stops as
  // soon as every violation is <= ceiling.
  TinSimplifier(const FaceGrid& g, const FaceRegions& regions, FaceOutlines outlines,
                const std::vector<FixedSegment>& fixed, double eps, std::size_t cap, double ceiling);
  TinSimplifier(const TinSimplifier&) = delete;
  TinSimplifier& operator=(const TinSimplifier&) = delete;

  // Greedy insertion, worst violation first. Returns the triangles (dense
  // vertex ids, three per triangle, oriented as the input's, in a fixed order).
  std::vector<std::uint32_t> run();
  // Triangles of the constrained triangulation of the outlines and face
  // borders alone: a lower bound on the result's size.
  std::size_t outline_triangles();
  // The largest depth error the result may have at a dense vertex off the outlines.
  double bound_used() const { return bound_used_; }

 private:
  std::size_t lattice_index(int x, int y) const { return cellbake::lattice_index(x, y, n_); }
  bool capped() const { return labelled_faces_ + 2 > cap_; }  // one more insertion would pass the cap

  // One step of refinement on the worst queued face; false when refinement is done.
  bool refine_step();
  // Inserts the worst free point of `top` (just popped) and queues the faces
  // around it; when it cannot be inserted, its error stays unresolved.
  void insert_free_point(const QueuedFace& top);
  // Gives `f` a fresh stamp and queues it when it violates the bound.
  void enqueue(Cdt::Face_handle f);
  // Re-inserts the farthest staircase point of every queued outline segment
  // whose depth violation still has to go; true when some outline changed.
  bool refine_outlines();
  // Remembers `p` as a Steiner point (re-inserted whenever the triangulation is rebuilt).
  void add_steiner(LatticePoint p);
  // Inserts a Steiner point unless it is already a vertex or lies on a
  // constraint (then returns a null handle); the new faces around it take the
  // region label of the face it fell in.
  Cdt::Vertex_handle insert_steiner(LatticePoint p);
  // Triangulates the constraints and queues every violating face.
  void build();
  // Triangulates the fixed and outline constraints (all end points inserted
  // at once, spatially sorted, then the constraints between them), re-inserts
  // the Steiner points and labels the components; the queue is left empty.
  void triangulate();
  // The end points and segments of the fixed and outline constraints (point
  // numbers into `points`), their owners added to owners_ (not finished).
  void collect_constraints(std::vector<CdtPoint>& points, std::vector<std::pair<std::size_t, std::size_t>>& segments);
  // Queues every violating face of the triangulation (evaluating a face scans
  // the lattice points it covers: the whole face in all, the costly part).
  void queue_all();
  // The labelled faces' triangles (see run()).
  std::vector<std::uint32_t> emit() const;

  const FaceGrid& g_;
  const FaceRegions& regions_;
  FaceOutlines outlines_;
  const std::vector<FixedSegment>& fixed_;
  int n_;
  double eps_;
  std::size_t cap_;
  double ceiling_;
  bool triangulated_ = false, queued_ = false;
  std::size_t labelled_faces_ = 0;  // triangles of the mesh (faces with a region)
  double bound_used_ = 0, unresolved_ = 0;
  std::vector<std::uint8_t> steiner_flag_;
  std::vector<LatticePoint> steiner_;
  Cdt cdt_;
  ConstraintOwners owners_;
  TinFaceMeter meter_;  // of cdt_ against the dense face
  std::uint32_t stamp_counter_ = 0;
  RefinementQueue queue_;
  static constexpr std::uint32_t kNoPoint = ~std::uint32_t{0};
  std::vector<std::uint32_t> point_id_of_;  // per lattice point: triangulate's point number (kNoPoint between calls)
};

}  // namespace cellbake
