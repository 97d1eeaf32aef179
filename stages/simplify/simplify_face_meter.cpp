// A triangulation face read against the dense face mesh (see
// simplify_face_meter.h; Garland & Heckbert 1995; Wilson 2002 ch. 5 §5.2.3).
#include "stages/simplify/simplify_face_meter.h"

#include <algorithm>
#include <cmath>

namespace cellbake {

TinFaceMeter::TinFaceMeter(const FaceGrid& g, const FaceRegions& regions, const FaceOutlines& outlines,
                           const ConstraintOwners& owners, const Cdt& cdt, double eps)
    : g_(g), regions_(regions), outlines_(outlines), owners_(owners), cdt_(cdt), n_(g.size), eps_(eps) {
  index_interior_lattice(outlines);
}

void TinFaceMeter::index_interior_lattice(const FaceOutlines& outlines) {
  const std::size_t points = std::size_t(n_ + 1) * (n_ + 1);
  interior_region_.assign(points, -1);
  interior_w_.assign(points, 0.0);
  for (int y = 0; y <= n_; ++y)
    for (int x = 0; x <= n_; ++x) {
      const std::size_t k = lattice_index(x, y);
      if (outlines.on_outline[k]) continue;
      const int i = std::min(x, n_ - 1), j = std::min(y, n_ - 1);
      const int l = label(i, j);
      if (l < 0) continue;
      interior_region_[k] = l;
      interior_w_[k] = g_.w[g_.vertex(i, j, x, y)];
    }
}

std::uint32_t TinFaceMeter::pick_vertex(int l, LatticePoint p, double cx, double cy) const {
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

std::uint32_t TinFaceMeter::pick_corner_vertex(Cdt::Face_handle f, int k, double cx, double cy) const {
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
      const ConstraintOwner* owner = owners_.find(lattice_index(p.x, p.y), lattice_index(q.x, q.y));
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

bool TinFaceMeter::unique_vertex(int l, LatticePoint p) const {
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

bool TinFaceMeter::corners(const Cdt::Face_handle& f, std::array<LatticePoint, 3>& p,
                           std::array<std::uint32_t, 3>& v) const {
  for (int k = 0; k < 3; ++k) p[k] = lattice_of(f->vertex(k)->point());
  const double cx = (p[0].x + p[1].x + p[2].x) / 3.0, cy = (p[0].y + p[1].y + p[2].y) / 3.0;
  for (int k = 0; k < 3; ++k) {
    v[k] = pick_corner_vertex(f, k, cx, cy);
    if (v[k] == kNoVertex) return false;
  }
  return true;
}

namespace {

// The x range [xl, xr] of the closed triangle p on row y (xl > xr: none).
void row_span(const std::array<LatticePoint, 3>& p, int y, double& xl, double& xr) {
  xl = 1e300, xr = -1e300;
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
}

}  // namespace

int TinFaceMeter::constrained_edge_through(const Cdt::Face_handle& f, const std::array<LatticePoint, 3>& p,
                                           LatticePoint q) const {
  int edge = -1;
  for (int e = 0; e < 3 && edge < 0; ++e) {
    const LatticePoint a = p[(e + 1) % 3], b = p[(e + 2) % 3];
    const long o = long(b.x - a.x) * (q.y - a.y) - long(b.y - a.y) * (q.x - a.x);
    if (o == 0 && cdt_.is_constrained({f, e})) edge = e;
  }
  return edge;
}

FaceViolation TinFaceMeter::evaluate(const Cdt::Face_handle& f) const {
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
    double xl, xr;
    row_span(p, y, xl, xr);
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
      const int edge = constrained_edge_through(f, p, q);
      if (edge < 0) {
        if (err > worst_free && (!outline || unique_vertex(l, q))) worst_free = err, out.free_at = q;
      } else if (err > worst_bound) {
        const LatticePoint a = p[(edge + 1) % 3], b = p[(edge + 2) % 3];
        const ConstraintOwner* owner = owners_.find(lattice_index(a.x, a.y), lattice_index(b.x, b.y));
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

}  // namespace cellbake
