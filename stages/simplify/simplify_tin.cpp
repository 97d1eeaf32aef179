// Greedy insertion into a constrained Delaunay triangulation (see
// simplify_tin.h; Garland & Heckbert 1995; Wilson 2002 ch. 5 §5.2.3).
#include "stages/simplify/simplify_tin.h"

#include <algorithm>
#include <array>

#include "stages/simplify/simplify_components.h"

namespace cellbake {

TinSimplifier::TinSimplifier(const FaceGrid& g, const FaceRegions& regions, FaceOutlines outlines,
                             const std::vector<FixedSegment>& fixed, double eps, std::size_t cap, double ceiling)
    : g_(g), regions_(regions), outlines_(std::move(outlines)), fixed_(fixed), n_(g.size), eps_(eps), cap_(cap),
      ceiling_(std::max(eps, ceiling)), steiner_flag_(std::size_t(n_ + 1) * (n_ + 1), 0),
      meter_(g, regions, outlines_, owners_, cdt_, eps), point_id_of_(std::size_t(n_ + 1) * (n_ + 1), kNoPoint) {}

std::vector<std::uint32_t> TinSimplifier::run() {
  if (!triangulated_) triangulate();
  if (!queued_) queue_all();
  while (refine_step()) {
  }
  bound_used_ = std::max({bound_used_, unresolved_, eps_});
  return emit();
}

std::size_t TinSimplifier::outline_triangles() {
  if (!triangulated_) triangulate();  // no queue yet: a caller may drop this simplifier for a looser one
  return labelled_faces_;
}

bool TinSimplifier::refine_step() {
  queue_.drop_stale_top();
  if (queue_.empty()) return false;
  const QueuedFace top = queue_.top();
  if (capped() && top.error <= ceiling_) {
    bound_used_ = std::max(bound_used_, top.error);
    return false;
  }
  const FaceViolation& v = top.violation;
  if (v.bound_error > 0 && v.bound_error >= v.free_error && refine_outlines()) {
    build();
    return true;
  }
  queue_.pop();
  insert_free_point(top);
  return true;
}

void TinSimplifier::insert_free_point(const QueuedFace& top) {
  const FaceViolation& v = top.violation;
  if (v.free_at.x < 0) {
    unresolved_ = std::max(unresolved_, top.error);  // an outline segment that cannot be refined further
    return;
  }
  add_steiner(v.free_at);
  const Cdt::Vertex_handle added = insert_steiner(v.free_at);
  if (added == Cdt::Vertex_handle()) {
    unresolved_ = std::max(unresolved_, top.error);
    return;
  }
  labelled_faces_ += 2;  // a split face (or two faces split at an edge) and flips within one component
  auto f = cdt_.incident_faces(added), end = f;
  do {
    if (!cdt_.is_infinite(f)) enqueue(f);
  } while (++f != end);
}

void TinSimplifier::enqueue(Cdt::Face_handle f) {
  f->info().stamp = ++stamp_counter_;
  const FaceViolation v = meter_.evaluate(f);
  if (v.worst() <= eps_) return;
  const LatticePoint at = v.free_error >= v.bound_error ? v.free_at : LatticePoint{0, 0};
  queue_.push({v.worst(), std::uint32_t(lattice_index(std::max(at.x, 0), std::max(at.y, 0))), f->info().stamp, f, v});
}

bool TinSimplifier::refine_outlines() {
  const double threshold = capped() ? ceiling_ : eps_;
  const std::vector<ChainSegment> segments = queue_.outline_segments_over(threshold);
  return !segments.empty() && refine_outline_segments(outlines_, segments, fixed_, n_);
}

void TinSimplifier::add_steiner(LatticePoint p) {
  std::uint8_t& f = steiner_flag_[lattice_index(p.x, p.y)];
  if (!f) {
    f = 1;
    steiner_.push_back(p);
  }
}

Cdt::Vertex_handle TinSimplifier::insert_steiner(LatticePoint p) {
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

void TinSimplifier::build() {
  triangulate();
  queue_all();
}

void TinSimplifier::triangulate() {
  queued_ = false;
  cdt_.clear();
  owners_.clear();
  queue_.clear();
  std::vector<CdtPoint> points;
  std::vector<std::pair<std::size_t, std::size_t>> segments;
  collect_constraints(points, segments);
  owners_.finish();
  cdt_.insert_constraints(points.begin(), points.end(), segments.begin(), segments.end());
  for (const LatticePoint& p : steiner_) insert_steiner(p);
  label_components(cdt_, regions_, n_);
  labelled_faces_ = 0;
  for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f)
    if (f->info().label >= 0) ++labelled_faces_;
  triangulated_ = true;
}

void TinSimplifier::collect_constraints(std::vector<CdtPoint>& points,
                                        std::vector<std::pair<std::size_t, std::size_t>>& segments) {
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
    owners_.add(lattice_index(s.a.x, s.a.y), lattice_index(s.b.x, s.b.y), {});
  }
  for (std::size_t c = 0; c < outlines_.chains.size(); ++c) {
    const OutlineChain& ch = outlines_.chains[c];
    std::size_t prev = 0;
    for (std::size_t k = 1; k < ch.points.size(); ++k)
      if (ch.kept[k]) {
        const LatticePoint a = ch.points[prev], b = ch.points[k];
        if (!(a == b)) {
          segments.emplace_back(point_id(a), point_id(b));
          owners_.add(lattice_index(a.x, a.y), lattice_index(b.x, b.y), {int(c), int(prev), int(k)});
        }
        prev = k;
      }
  }
  for (const CdtPoint& p : points) point_id_of_[lattice_index(int(p.x()), int(p.y()))] = kNoPoint;
}

void TinSimplifier::queue_all() {
  std::vector<Cdt::Face_handle> faces;
  for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) faces.push_back(f);
  for (const Cdt::Face_handle& f : faces) enqueue(f);
  queued_ = true;
}

std::vector<std::uint32_t> TinSimplifier::emit() const {
  std::vector<std::uint32_t> out;
  std::array<LatticePoint, 3> p;
  std::array<std::uint32_t, 3> v;
  // Faces in a fixed order (by lattice corners) so the output does not depend on CGAL's storage order.
  std::vector<std::array<std::uint32_t, 6>> tris;
  for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) {
    if (f->info().label < 0 || !meter_.corners(f, p, v)) continue;
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

}  // namespace cellbake
