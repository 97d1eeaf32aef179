// Simplification of dense face meshes (see simplify.h for the contract;
// Wilson 2002 ch. 5 §5.2.3 for the error model).
//
// 1. Border rule (simplify_border): which face-border vertices survive, decided
//    from data both neighbouring faces hold bit for bit.
// 2. Outlines (simplify_outline): the staircase outlines of the surface regions
//    (silhouettes, skins, coverage edges) are cut into chains, each straightened
//    once by Douglas-Peucker within boundary_error_px, so both sides of a
//    silhouette get the same line, and repaired until no segments cross.
// 3. Interior: a constrained Delaunay triangulation (CGAL, exact predicates on
//    integer lattice points) of the kept outline and border points, refined by
//    greedy insertion (Garland & Heckbert 1995, "Fast polygonal approximation
//    of terrains and height fields"): every triangle whose plane in (x, y, 1/z)
//    screen space misses one of its region's dense vertices by more than the
//    relative depth bound is queued by its worst miss; the worst in the queue
//    is inserted first, until none is left or the triangle cap is reached with
//    every miss within the cap's looser bound. A world-space plane is an exact
//    plane in (x, y, 1/z), so flat surfaces end as a few large triangles. A
//    violation on a straightened outline segment re-inserts that segment's
//    farthest staircase point instead (all such segments at once, then the
//    triangulation is rebuilt).
// Each triangle belongs to the region that holds most of its triangulation
// component (the cells bounded by constraints) and takes, at every corner, the
// dense vertex of that region there (the pixel in the triangle's direction
// where the region meets itself across a skin), so the two sides of a
// silhouette use their own depths on one shared screen-space line.
#include "stages/simplify/simplify.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <climits>
#include <memory>
#include <optional>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "stages/simplify/simplify_border.h"
#include "stages/simplify/simplify_grid.h"
#include "stages/simplify/simplify_outline.h"

namespace cellbake {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
struct FaceInfo {
  int label = INT_MIN;
  std::uint32_t stamp = 0;  // changes whenever the face is (re)made, for the refinement queue
};
using FaceBaseWithInfo = CGAL::Triangulation_face_base_with_info_2<FaceInfo, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel, FaceBaseWithInfo>;
using Tds = CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_2<Kernel>, FaceBase>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::No_constraint_intersection_requiring_constructions_tag>;
using CdtPoint = Cdt::Point;

// Owner of a constraint: a chain segment [i, j], or the face border (chain -1).
struct ConstraintOwner {
  int chain = -1, i = 0, j = 0;
};

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

// A triangle waiting in the refinement queue; stale once its face was
// destroyed or changed (the stamp no longer matches).
struct QueuedFace {
  double error = 0;
  std::uint32_t tie = 0;  // lattice index of the violating point: deterministic order among equal errors
  std::uint32_t stamp = 0;
  Cdt::Face_handle face;
  FaceViolation violation;
};

// Max-heap order: larger error first, then the smaller lattice index.
bool queued_before(const QueuedFace& a, const QueuedFace& b) {
  if (a.error != b.error) return a.error < b.error;
  if (a.tie != b.tie) return a.tie > b.tie;
  return a.stamp > b.stamp;
}

class TinSimplifier {
 public:
  // `cap` and `ceiling`: once the mesh has at least `cap` triangles, refinement
  // stops as soon as every violation is <= ceiling.
  TinSimplifier(const FaceGrid& g, const FaceRegions& regions, FaceOutlines outlines,
                const std::vector<FixedSegment>& fixed, double eps, std::size_t cap, double ceiling)
      : g_(g), regions_(regions), outlines_(std::move(outlines)), fixed_(fixed), n_(g.size), eps_(eps), cap_(cap),
        ceiling_(std::max(eps, ceiling)), steiner_flag_(std::size_t(n_ + 1) * (n_ + 1), 0),
        point_id_of_(std::size_t(n_ + 1) * (n_ + 1), kNoPoint) {
    index_interior_lattice();
  }

  // Greedy insertion, worst violation first (Garland & Heckbert 1995). Returns
  // the triangles (dense vertex ids, three per triangle).
  std::vector<std::uint32_t> run() {
    if (!triangulated_) triangulate();
    if (!queued_) queue_all();
    for (;;) {
      while (!queue_.empty() && stale(queue_.front())) pop();
      if (queue_.empty()) break;
      const QueuedFace top = queue_.front();
      if (capped() && top.error <= ceiling_) {
        bound_used_ = std::max(bound_used_, top.error);
        break;
      }
      const FaceViolation& v = top.violation;
      if (v.bound_error > 0 && v.bound_error >= v.free_error && refine_outlines()) {
        build();
        continue;
      }
      pop();
      if (v.free_at.x < 0) {
        unresolved_ = std::max(unresolved_, top.error);  // an outline segment that cannot be refined further
        continue;
      }
      add_steiner(v.free_at);
      const Cdt::Vertex_handle added = insert_steiner(v.free_at);
      if (added == Cdt::Vertex_handle()) {
        unresolved_ = std::max(unresolved_, top.error);
        continue;
      }
      labelled_faces_ += 2;  // a split face (or two faces split at an edge) and flips within one component
      auto f = cdt_.incident_faces(added), end = f;
      do {
        if (!cdt_.is_infinite(f)) enqueue(f);
      } while (++f != end);
    }
    bound_used_ = std::max({bound_used_, unresolved_, eps_});
    return emit();
  }

  // Triangles of the constrained triangulation of the outlines and face
  // borders alone: a lower bound on the result's size.
  std::size_t outline_triangles() {
    if (!triangulated_) triangulate();  // no queue yet: a caller may drop this simplifier for a looser one
    return labelled_faces_;
  }

  // The largest depth error the result may have at a dense vertex off the outlines.
  double bound_used() const { return bound_used_; }

 private:
  std::size_t lattice_index(int x, int y) const { return std::size_t(y) * (n_ + 1) + x; }
  static std::uint64_t key(std::size_t a, std::size_t b) {
    return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
  }
  static LatticePoint lattice_of(const CdtPoint& p) { return {int(std::lround(p.x())), int(std::lround(p.y()))}; }
  int label(int i, int j) const { return regions_.label[std::size_t(j) * n_ + i]; }
  bool capped() const { return labelled_faces_ + 2 > cap_; }  // one more insertion would pass the cap

  // The owner of the constraint with key k, or null.
  const ConstraintOwner* owner_of(std::uint64_t k) const {
    const auto it = std::lower_bound(owners_.begin(), owners_.end(), k,
                                     [](const KeyedOwner& o, std::uint64_t key) { return o.first < key; });
    return it != owners_.end() && it->first == k ? &it->second : nullptr;
  }

  // Lattice points off every outline: all pixels around one share a region
  // and a vertex (or none is covered), so their vertex needs no search.
  void index_interior_lattice() {
    const std::size_t points = std::size_t(n_ + 1) * (n_ + 1);
    interior_region_.assign(points, -1);
    interior_w_.assign(points, 0.0);
    for (int y = 0; y <= n_; ++y)
      for (int x = 0; x <= n_; ++x) {
        const std::size_t k = lattice_index(x, y);
        if (outlines_.on_outline[k]) continue;
        const int i = std::min(x, n_ - 1), j = std::min(y, n_ - 1);
        const int l = label(i, j);
        if (l < 0) continue;
        interior_region_[k] = l;
        interior_w_[k] = g_.w[g_.vertex(i, j, x, y)];
      }
  }

  void pop() {
    std::pop_heap(queue_.begin(), queue_.end(), queued_before);
    queue_.pop_back();
  }
  bool stale(const QueuedFace& q) const { return q.face->info().stamp != q.stamp; }

  // Gives `f` a fresh stamp and queues it when it violates the bound.
  void enqueue(Cdt::Face_handle f) {
    f->info().stamp = ++stamp_counter_;
    const FaceViolation v = evaluate(f);
    if (v.worst() <= eps_) return;
    const LatticePoint at = v.free_error >= v.bound_error ? v.free_at : LatticePoint{0, 0};
    queue_.push_back({v.worst(), std::uint32_t(lattice_index(std::max(at.x, 0), std::max(at.y, 0))),
                      f->info().stamp, f, v});
    std::push_heap(queue_.begin(), queue_.end(), queued_before);
  }

  // Re-inserts the farthest staircase point of every queued outline segment
  // whose depth violation still has to go; true when some outline changed.
  bool refine_outlines() {
    const double threshold = capped() ? ceiling_ : eps_;
    std::vector<ChainSegment> segments;
    for (const QueuedFace& q : queue_)
      if (!stale(q) && q.violation.bound_error > threshold)
        segments.push_back({q.violation.bound_owner.chain, q.violation.bound_owner.i, q.violation.bound_owner.j});
    std::sort(segments.begin(), segments.end(), [](const ChainSegment& a, const ChainSegment& b) {
      return std::tie(a.chain, a.i, a.j) < std::tie(b.chain, b.i, b.j);
    });
    segments.erase(std::unique(segments.begin(), segments.end(),
                               [](const ChainSegment& a, const ChainSegment& b) {
                                 return a.chain == b.chain && a.i == b.i && a.j == b.j;
                               }),
                   segments.end());
    return !segments.empty() && refine_outline_segments(outlines_, segments, fixed_, n_);
  }

  void add_steiner(LatticePoint p) {
    std::uint8_t& f = steiner_flag_[lattice_index(p.x, p.y)];
    if (!f) {
      f = 1;
      steiner_.push_back(p);
    }
  }

  // Inserts a Steiner point unless it is already a vertex or lies on a
  // constraint (then returns a null handle); the new faces around it take the
  // region label of the face it fell in.
  Cdt::Vertex_handle insert_steiner(LatticePoint p) {
    Cdt::Locate_type lt;
    int li = 0;
    const CdtPoint q(p.x, p.y);
    const Cdt::Face_handle f = cdt_.locate(q, lt, li);
    if (lt == Cdt::VERTEX || lt == Cdt::OUTSIDE_CONVEX_HULL || lt == Cdt::OUTSIDE_AFFINE_HULL) return {};
    if (lt == Cdt::EDGE && cdt_.is_constrained({f, li})) return {};
    const int l = f->info().label;
    const Cdt::Vertex_handle v = cdt_.insert(q, f);
    auto g = cdt_.incident_faces(v), end = g;
    do {
      g->info().label = l;
    } while (++g != end);
    return v;
  }

  // Triangulates the constraints and queues every violating face.
  void build() {
    triangulate();
    queue_all();
  }

  // Triangulates the fixed and outline constraints (all end points inserted
  // at once, spatially sorted, then the constraints between them), re-inserts
  // the Steiner points and labels the components; the queue is left empty.
  void triangulate() {
    queued_ = false;
    cdt_.clear();
    owners_.clear();
    queue_.clear();
    std::vector<CdtPoint> points;
    std::vector<std::pair<std::size_t, std::size_t>> segments;
    auto point_id = [&](LatticePoint p) {
      std::uint32_t& id = point_id_of_[lattice_index(p.x, p.y)];
      if (id == kNoPoint) {
        id = std::uint32_t(points.size());
        points.emplace_back(p.x, p.y);
      }
      return std::size_t(id);
    };
    for (const FixedSegment& s : fixed_) {
      segments.emplace_back(point_id(s.a), point_id(s.b));
      owners_.push_back({key(lattice_index(s.a.x, s.a.y), lattice_index(s.b.x, s.b.y)), {}});
    }
    for (std::size_t c = 0; c < outlines_.chains.size(); ++c) {
      const OutlineChain& ch = outlines_.chains[c];
      std::size_t prev = 0;
      for (std::size_t k = 1; k < ch.points.size(); ++k)
        if (ch.kept[k]) {
          const LatticePoint a = ch.points[prev], b = ch.points[k];
          if (!(a == b)) {
            segments.emplace_back(point_id(a), point_id(b));
            owners_.push_back({key(lattice_index(a.x, a.y), lattice_index(b.x, b.y)), {int(c), int(prev), int(k)}});
          }
          prev = k;
        }
    }
    for (const CdtPoint& p : points) point_id_of_[lattice_index(int(p.x()), int(p.y()))] = kNoPoint;
    // By key; of a key given twice, the last owner stands.
    std::stable_sort(owners_.begin(), owners_.end(),
                     [](const KeyedOwner& a, const KeyedOwner& b) { return a.first < b.first; });
    std::size_t kept = 0;
    for (std::size_t i = 0; i < owners_.size(); ++i) {
      if (i + 1 < owners_.size() && owners_[i + 1].first == owners_[i].first) continue;
      owners_[kept++] = owners_[i];
    }
    owners_.resize(kept);
    cdt_.insert_constraints(points.begin(), points.end(), segments.begin(), segments.end());
    for (const LatticePoint& p : steiner_) insert_steiner(p);
    label_components();
    labelled_faces_ = 0;
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f)
      if (f->info().label >= 0) ++labelled_faces_;
    triangulated_ = true;
  }

  // Queues every violating face of the triangulation (evaluating a face scans
  // the lattice points it covers: the whole face in all, the costly part).
  void queue_all() {
    std::vector<Cdt::Face_handle> faces;
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) faces.push_back(f);
    for (const Cdt::Face_handle& f : faces) enqueue(f);
    queued_ = true;
  }

  // Components of finite faces joined across unconstrained edges; each takes
  // the region label of most of the pixel centres inside its triangles (the
  // pixel under a triangle's centroid, weighted by area, breaks ties and
  // labels components too thin to hold a pixel centre), -1 for background.
  void label_components() {
    for (auto f = cdt_.all_faces_begin(); f != cdt_.all_faces_end(); ++f) f->info().label = INT_MIN;
    std::vector<Cdt::Face_handle> stack, members;
    struct Vote {
      int label;
      std::size_t centres;
      double area;
    };
    std::vector<Vote> votes;
    auto vote = [&](int l, std::size_t centres, double area) {
      auto it = std::find_if(votes.begin(), votes.end(), [&](const Vote& v) { return v.label == l; });
      if (it == votes.end()) votes.push_back({l, centres, area});
      else it->centres += centres, it->area += area;
    };
    for (auto start = cdt_.finite_faces_begin(); start != cdt_.finite_faces_end(); ++start) {
      if (start->info().label != INT_MIN) continue;
      members.clear();
      votes.clear();
      start->info().label = INT_MIN + 1;  // visiting
      stack.push_back(start);
      while (!stack.empty()) {
        const Cdt::Face_handle f = stack.back();
        stack.pop_back();
        members.push_back(f);
        const std::array<LatticePoint, 3> p{lattice_of(f->vertex(0)->point()), lattice_of(f->vertex(1)->point()),
                                            lattice_of(f->vertex(2)->point())};
        const double area =
            std::abs(double(p[1].x - p[0].x) * (p[2].y - p[0].y) - double(p[1].y - p[0].y) * (p[2].x - p[0].x));
        const int px = std::clamp(int(std::floor((p[0].x + p[1].x + p[2].x) / 3.0)), 0, n_ - 1);
        const int py = std::clamp(int(std::floor((p[0].y + p[1].y + p[2].y) / 3.0)), 0, n_ - 1);
        vote(label(px, py), 0, area);
        vote_pixel_centres(p, vote);
        for (int e = 0; e < 3; ++e) {
          const Cdt::Face_handle nb = f->neighbor(e);
          if (cdt_.is_infinite(nb) || cdt_.is_constrained({f, e}) || nb->info().label != INT_MIN) continue;
          nb->info().label = INT_MIN + 1;
          stack.push_back(nb);
        }
      }
      const Vote* best = &votes.front();
      for (const Vote& v : votes)
        if (v.centres > best->centres || (v.centres == best->centres && v.area > best->area)) best = &v;
      for (const Cdt::Face_handle& f : members) f->info().label = best->label;
    }
  }

  // Calls vote(label, count, 0) for the pixels whose centre lies in the closed
  // triangle p: once per run of equal labels along a row (count: its length).
  template <typename VoteFn>
  void vote_pixel_centres(const std::array<LatticePoint, 3>& p, VoteFn&& vote) const {
    const int ymin = std::min({p[0].y, p[1].y, p[2].y}), ymax = std::max({p[0].y, p[1].y, p[2].y});
    for (int py = std::max(ymin, 0); py < std::min(ymax, n_); ++py) {
      const double y = py + 0.5;
      double xl = 1e300, xr = -1e300;
      for (int e = 0; e < 3; ++e) {
        const LatticePoint a = p[e], b = p[(e + 1) % 3];
        if ((a.y - y) * (b.y - y) > 0 || a.y == b.y) continue;
        const double x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
        xl = std::min(xl, x), xr = std::max(xr, x);
      }
      if (!(xl <= xr)) continue;
      const int x0 = std::max(0, int(std::ceil(xl - 0.5))), x1 = std::min(n_ - 1, int(std::floor(xr - 0.5)));
      for (int px = x0; px <= x1;) {  // one call per run of equal labels
        const int l = label(px, py);
        int end = px + 1;
        while (end <= x1 && label(end, py) == l) ++end;
        vote(l, std::size_t(end - px), 0.0);
        px = end;
      }
    }
  }

  // Dense vertex of region l at lattice point p for a triangle whose centroid is (cx, cy).
  std::uint32_t pick_vertex(int l, LatticePoint p, double cx, double cy) const {
    std::uint32_t first = kNoVertex;
    bool unique = true;
    for (int j = p.y - 1; j <= p.y; ++j)
      for (int i = p.x - 1; i <= p.x; ++i) {
        if (i < 0 || j < 0 || i >= n_ || j >= n_ || label(i, j) != l) continue;
        const std::uint32_t v = g_.vertex(i, j, p.x, p.y);
        if (first == kNoVertex) first = v;
        else if (v != first) unique = false;
      }
    if (unique) return first;
    const int i = p.x + (cx < p.x ? -1 : 0), j = p.y + (cy < p.y ? -1 : 0);
    if (i >= 0 && j >= 0 && i < n_ && j < n_ && label(i, j) == l) return g_.vertex(i, j, p.x, p.y);
    return first;
  }

  // Dense vertex of corner k of face f where the region meets itself at that
  // point with several vertices (the end of a skin, a pinch): the constraint
  // met first turning counter-clockwise about the corner starts with an
  // outline step d; the face lies on its clockwise side, in the pixel there.
  std::uint32_t pick_corner_vertex(Cdt::Face_handle f, int k, double cx, double cy) const {
    const int l = f->info().label;
    const Cdt::Vertex_handle v = f->vertex(k);
    const LatticePoint p = lattice_of(v->point());
    const std::uint32_t simple = pick_vertex(l, p, cx, cy);
    if (simple == kNoVertex || unique_vertex(l, p)) return simple;
    Cdt::Face_handle g = f;
    int gk = k;
    for (int guard = 0; guard < 64; ++guard) {
      const int e = Cdt::ccw(gk);
      if (cdt_.is_constrained({g, e})) {
        const LatticePoint q = lattice_of(g->vertex(Cdt::cw(gk))->point());
        LatticePoint step{(q.x > p.x) - (q.x < p.x), (q.y > p.y) - (q.y < p.y)};
        const ConstraintOwner* owner = owner_of(key(lattice_index(p.x, p.y), lattice_index(q.x, q.y)));
        if (owner && owner->chain >= 0) {
          const OutlineChain& c = outlines_.chains[owner->chain];
          const LatticePoint next = c.points[owner->i] == p ? c.points[owner->i + 1] : c.points[owner->j - 1];
          step = {next.x - p.x, next.y - p.y};
        }
        // Pixel clockwise of the step (math orientation of the lattice coordinates).
        int i = p.x, j = p.y;
        if (step.x > 0) {
          j -= 1;
        } else if (step.y > 0) {
        } else if (step.x < 0) {
          i -= 1;
        } else {
          i -= 1, j -= 1;
        }
        if (i >= 0 && j >= 0 && i < n_ && j < n_ && label(i, j) == l) return g_.vertex(i, j, p.x, p.y);
        return simple;
      }
      const Cdt::Face_handle next = g->neighbor(Cdt::ccw(gk));
      if (cdt_.is_infinite(next) || next == f) break;
      gk = next->index(v);
      g = next;
    }
    return simple;
  }

  bool unique_vertex(int l, LatticePoint p) const {
    std::uint32_t first = kNoVertex;
    for (int j = p.y - 1; j <= p.y; ++j)
      for (int i = p.x - 1; i <= p.x; ++i) {
        if (i < 0 || j < 0 || i >= n_ || j >= n_ || label(i, j) != l) continue;
        const std::uint32_t v = g_.vertex(i, j, p.x, p.y);
        if (first != kNoVertex && v != first) return false;
        first = v;
      }
    return true;
  }

  bool corners(const Cdt::Face_handle& f, std::array<LatticePoint, 3>& p, std::array<std::uint32_t, 3>& v) const {
    for (int k = 0; k < 3; ++k) p[k] = lattice_of(f->vertex(k)->point());
    const double cx = (p[0].x + p[1].x + p[2].x) / 3.0, cy = (p[0].y + p[1].y + p[2].y) / 3.0;
    for (int k = 0; k < 3; ++k) {
      v[k] = pick_corner_vertex(f, k, cx, cy);
      if (v[k] == kNoVertex) return false;
    }
    return true;
  }

  // The worst violations of face f (see FaceViolation); none for background.
  FaceViolation evaluate(const Cdt::Face_handle& f) const {
    FaceViolation out;
    std::array<LatticePoint, 3> p;
    std::array<std::uint32_t, 3> v;
    const int l = f->info().label;
    if (l < 0 || !corners(f, p, v)) return out;
    const double w0 = g_.w[v[0]], w1 = g_.w[v[1]], w2 = g_.w[v[2]];
    const double x0 = p[0].x, y0 = p[0].y;
    const double orient = double(p[1].x - p[0].x) * (p[2].y - p[0].y) - double(p[1].y - p[0].y) * (p[2].x - p[0].x);
    if (orient == 0) return out;
    const double alpha = ((w1 - w0) * (p[2].y - y0) - (w2 - w0) * (p[1].y - y0)) / orient;
    const double beta = ((w2 - w0) * (p[1].x - x0) - (w1 - w0) * (p[2].x - x0)) / orient;
    const double gamma = w0 - alpha * x0 - beta * y0;
    const double cx = (p[0].x + p[1].x + p[2].x) / 3.0, cy = (p[0].y + p[1].y + p[2].y) / 3.0;
    double worst_free = eps_, worst_bound = eps_;
    const int ymin = std::min({p[0].y, p[1].y, p[2].y}), ymax = std::max({p[0].y, p[1].y, p[2].y});
    for (int y = ymin; y <= ymax; ++y) {
      double xl = 1e300, xr = -1e300;
      for (int e = 0; e < 3; ++e) {
        const LatticePoint a = p[e], b = p[(e + 1) % 3];
        if (a.y == b.y) {
          if (a.y == y) xl = std::min({xl, double(a.x), double(b.x)}), xr = std::max({xr, double(a.x), double(b.x)});
          continue;
        }
        if ((a.y - y) * (b.y - y) > 0) continue;
        const double x = a.x + double(y - a.y) * (b.x - a.x) / (b.y - a.y);
        xl = std::min(xl, x), xr = std::max(xr, x);
      }
      if (!(xl <= xr)) continue;
      const int x_end = int(std::floor(xr + 1e-9));
      for (int x = int(std::ceil(xl - 1e-9)); x <= x_end; ++x) {
        const std::size_t k = lattice_index(x, y);
        const bool outline = outlines_.on_outline[k] != 0;
        double w;
        if (!outline) {
          if (interior_region_[k] != l) continue;
          w = interior_w_[k];
        } else {
          // Outline points too: a straightened outline must not bridge a skin
          // (where the region meets itself there, the side the triangle is on).
          const std::uint32_t dv = pick_vertex(l, {x, y}, cx, cy);
          if (dv == kNoVertex) continue;
          w = g_.w[dv];
        }
        const double wp = alpha * x + beta * y + gamma;
        if (wp > 0 && std::abs(w - wp) <= eps_ * wp) continue;
        const LatticePoint q{x, y};
        if (q == p[0] || q == p[1] || q == p[2]) continue;
        const double err = wp > 0 ? std::abs(w - wp) / wp : 1e300;
        // On a constrained edge of this triangle?
        int edge = -1;
        for (int e = 0; e < 3 && edge < 0; ++e) {
          const LatticePoint a = p[(e + 1) % 3], b = p[(e + 2) % 3];
          const long o = long(b.x - a.x) * (q.y - a.y) - long(b.y - a.y) * (q.x - a.x);
          if (o == 0 && cdt_.is_constrained({f, e})) edge = e;
        }
        if (edge < 0) {
          if (err > worst_free && (!outline || unique_vertex(l, q))) worst_free = err, out.free_at = q;
        } else if (err > worst_bound) {
          const LatticePoint a = p[(edge + 1) % 3], b = p[(edge + 2) % 3];
          const ConstraintOwner* owner = owner_of(key(lattice_index(a.x, a.y), lattice_index(b.x, b.y)));
          if (owner && owner->chain >= 0) {
            worst_bound = err;
            out.bound_owner = *owner;
          }
        }
      }
    }
    if (out.free_at.x >= 0) out.free_error = worst_free;
    if (worst_bound > eps_) out.bound_error = worst_bound;
    return out;
  }

  std::vector<std::uint32_t> emit() const {
    std::vector<std::uint32_t> out;
    std::array<LatticePoint, 3> p;
    std::array<std::uint32_t, 3> v;
    // Faces in a fixed order (by lattice corners) so the output does not depend on CGAL's storage order.
    std::vector<std::array<std::uint32_t, 6>> tris;
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) {
      if (f->info().label < 0 || !corners(f, p, v)) continue;
      const long orient = long(p[1].x - p[0].x) * (p[2].y - p[0].y) - long(p[1].y - p[0].y) * (p[2].x - p[0].x);
      if ((orient > 0 ? 1 : -1) != g_.orientation) std::swap(v[1], v[2]), std::swap(p[1], p[2]);
      // Rotate so the smallest lattice index comes first.
      std::array<std::size_t, 3> idx{lattice_index(p[0].x, p[0].y), lattice_index(p[1].x, p[1].y),
                                     lattice_index(p[2].x, p[2].y)};
      const int r = int(std::min_element(idx.begin(), idx.end()) - idx.begin());
      tris.push_back({std::uint32_t(idx[r]), std::uint32_t(idx[(r + 1) % 3]), std::uint32_t(idx[(r + 2) % 3]), v[r],
                      v[(r + 1) % 3], v[(r + 2) % 3]});
    }
    std::sort(tris.begin(), tris.end());
    out.reserve(tris.size() * 3);
    for (const auto& t : tris) out.insert(out.end(), {t[3], t[4], t[5]});
    return out;
  }

  const FaceGrid& g_;
  const FaceRegions& regions_;
  FaceOutlines outlines_;
  const std::vector<FixedSegment>& fixed_;
  int n_;
  double eps_;
  std::size_t cap_;
  double ceiling_;
  bool triangulated_ = false, queued_ = false;
  std::size_t labelled_faces_ = 0;       // triangles of the mesh (faces with a region)
  double bound_used_ = 0, unresolved_ = 0;
  std::vector<std::int32_t> interior_region_;  // per lattice point off the outlines: its region, or -1
  std::vector<double> interior_w_;             // and the inverse depth of its vertex
  std::vector<std::uint8_t> steiner_flag_;
  std::vector<LatticePoint> steiner_;
  Cdt cdt_;
  std::uint32_t stamp_counter_ = 0;
  std::vector<QueuedFace> queue_;  // a max-heap by queued_before
  using KeyedOwner = std::pair<std::uint64_t, ConstraintOwner>;
  std::vector<KeyedOwner> owners_;  // constraint owners by key (ascending, unique)
  static constexpr std::uint32_t kNoPoint = ~std::uint32_t{0};
  std::vector<std::uint32_t> point_id_of_;  // per lattice point: triangulate's point number (kNoPoint between calls)
};

std::vector<std::uint32_t> dense_triangles(const FaceMesh& in) { return in.indices; }

FaceMesh compact(const FaceMesh& in, const std::vector<std::uint32_t>& tris) {
  FaceMesh out;
  std::vector<std::uint32_t> remap(in.positions.size(), kNoVertex);
  out.indices.reserve(tris.size());
  for (std::uint32_t v : tris) {
    if (remap[v] == kNoVertex) {
      remap[v] = std::uint32_t(out.positions.size());
      out.positions.push_back(in.positions[v]);
      out.uvs.push_back(in.uvs[v]);
    }
    out.indices.push_back(remap[v]);
  }
  return out;
}

}  // namespace

// What measuring a result needs of the dense mesh it came from: the dense
// vertices, the grid, the regions and the traced (not straightened) outlines.
struct DenseFaceAnalysis {
  std::optional<FaceMesh> owned;
  const FaceMesh* in = nullptr;
  int face_size = 0;
  FaceGrid grid;
  std::optional<FaceRegions> regions;  // unset (and traced too) when the face is too small to simplify
  std::optional<FaceOutlines> traced;

  SimplifyError measure(const FaceMesh& simplified) const {
    return regions ? measure_simplification_error(*in, grid, *regions, *traced, simplified)
                   : measure_simplification_error(*in, simplified, face_size);
  }
};

// The state between the two steps: the dense mesh's analysis (at a stable
// address: the simplifier refers to its grid and regions), the outlines and
// their triangulation, kept so that finishing continues where bounding stopped.
struct FaceSimplification::State {
  std::unique_ptr<DenseFaceAnalysis> dense = std::make_unique<DenseFaceAnalysis>();
  SimplifyParams params;
  std::vector<FixedSegment> fixed;
  std::unique_ptr<TinSimplifier> tin;
  std::size_t triangles_in = 0;
};

FaceSimplification::FaceSimplification(const FaceMesh& in, int face_size, const SimplifyParams& params)
    : state_(std::make_unique<State>()) {
  state_->dense->in = &in;
  start(face_size, params);
}

FaceSimplification::FaceSimplification(FaceMesh&& in, int face_size, const SimplifyParams& params)
    : state_(std::make_unique<State>()) {
  DenseFaceAnalysis& dense = *state_->dense;
  dense.owned.emplace(std::move(in));
  dense.in = &*dense.owned;
  start(face_size, params);
}

FaceSimplification::~FaceSimplification() = default;
FaceSimplification::FaceSimplification(FaceSimplification&&) noexcept = default;
FaceSimplification& FaceSimplification::operator=(FaceSimplification&&) noexcept = default;

void FaceSimplification::start(int face_size, const SimplifyParams& params) {
  if (!(params.depth_error_relative >= 0))
    throw std::invalid_argument("simplify_face_mesh: depth_error_relative must be >= 0");
  if (!(params.boundary_error_px >= 0))
    throw std::invalid_argument("simplify_face_mesh: boundary_error_px must be >= 0");
  if (!(params.max_depth_error_factor >= 1))
    throw std::invalid_argument("simplify_face_mesh: max_depth_error_factor must be >= 1");
  State& st = *state_;
  DenseFaceAnalysis& dense = *st.dense;
  dense.face_size = face_size;
  st.params = params;
  st.triangles_in = dense.in->triangle_count();
  dense.grid = read_face_grid(*dense.in, face_size);
  if (face_size < 4) {  // too small to simplify: the dense mesh is the result
    outline_triangles_ = dense.in->triangle_count();
    return;
  }
  dense.regions = label_face_regions(dense.grid);
  for (const BorderPiece& p : split_face_border(*dense.in, dense.grid, params.depth_error_relative)) {
    if (!p.covered) continue;
    const auto a = border_point(p.side, p.a, face_size), b = border_point(p.side, p.b, face_size);
    st.fixed.push_back({{a[0], a[1]}, {b[0], b[1]}});
  }
  dense.traced = trace_face_outlines(dense.grid, *dense.regions);
  const double eps = params.depth_error_relative, ceiling = eps * params.max_depth_error_factor;
  const auto simplifier = [&](double outline_depth_error) {
    FaceOutlines outlines = *dense.traced;
    straighten_face_outlines(outlines, st.fixed, params.boundary_error_px, outline_depth_error, face_size);
    return std::make_unique<TinSimplifier>(dense.grid, *dense.regions, std::move(outlines), st.fixed, eps,
                                           params.max_triangles, ceiling);
  };
  st.tin = simplifier(eps);
  // When the outlines alone exceed the cap, the cap's looser bound applies
  // from the start, to their straightening too.
  if (st.tin->outline_triangles() > params.max_triangles && ceiling > eps) st.tin = simplifier(ceiling);
  outline_triangles_ = st.tin->outline_triangles();
  // What waits for finish() needs only the dense vertices, to measure too (a
  // third of an owned dense mesh's memory is its triangles).
  if (dense.owned) std::vector<std::uint32_t>().swap(dense.owned->indices);
}

std::size_t FaceSimplification::outline_triangles() const { return outline_triangles_; }

SimplifyResult FaceSimplification::finish() && {
  SimplifyRuler ruler;
  const bool measure = state_ && state_->params.measure_error;
  SimplifyResult result = std::move(*this).finish(ruler);
  if (measure) result.achieved = ruler.measure(result.mesh);
  return result;
}

SimplifyResult FaceSimplification::finish(SimplifyRuler& ruler) && {
  if (!state_) throw std::logic_error("FaceSimplification::finish: already finished");
  std::unique_ptr<State> st = std::move(state_);
  SimplifyResult result;
  const FaceMesh& in = *st->dense->in;
  result.triangles_in = st->triangles_in;
  result.outline_triangles = outline_triangles_;
  double eps = st->params.depth_error_relative;
  if (st->tin) {
    result.mesh = compact(in, st->tin->run());
    eps = st->tin->bound_used();
  } else {
    result.mesh = compact(in, dense_triangles(in));
  }
  result.triangles_out = result.mesh.triangle_count();
  result.depth_error_bound_used = eps;
  result.cap_forced_larger_error = eps > st->params.depth_error_relative;
  st->tin.reset();  // it refers to the analysis handed over below
  ruler.dense_ = std::move(st->dense);
  return result;
}

SimplifyRuler::SimplifyRuler() = default;
SimplifyRuler::~SimplifyRuler() = default;
SimplifyRuler::SimplifyRuler(SimplifyRuler&&) noexcept = default;
SimplifyRuler& SimplifyRuler::operator=(SimplifyRuler&&) noexcept = default;

SimplifyError SimplifyRuler::measure(const FaceMesh& simplified) const {
  if (!dense_) throw std::logic_error("SimplifyRuler::measure: holds no dense mesh");
  return dense_->measure(simplified);
}

SimplifyResult simplify_face_mesh(const FaceMesh& in, int face_size, const SimplifyParams& params) {
  return FaceSimplification(in, face_size, params).finish();
}

}  // namespace cellbake
