// Voronoi best-next-view candidates (Wilson 2002, ch. 3, §3.4.2.5, Figure
// 3.25): the Voronoi vertices of the sample positions inside the navigable
// region and the crossings of Voronoi edges with its boundary. The Voronoi
// diagram is the dual of CGAL's Delaunay triangulation (exact predicates,
// double constructions); the collinear case, where CGAL has no faces, is the
// set of bisectors of consecutive samples. See sample_candidates.h.
#include "stages/sample/sample_candidates.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cellbake {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Delaunay = CGAL::Delaunay_triangulation_2<Kernel>;

constexpr double kInf = std::numeric_limits<double>::infinity();

bool lex_less(const Vec2d& a, const Vec2d& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
double distance(const Vec2d& a, const Vec2d& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double coord(const Vec2d& p, int axis) { return axis == 0 ? p.x : p.y; }
bool finite(const Vec2d& p) { return std::isfinite(p.x) && std::isfinite(p.y); }

// Sorts `points` (x, then y) and drops every point closer than eps to an
// earlier kept one. The kept points stay sorted by x, so only those with
// x >= p.x - eps need a look.
std::vector<Vec2d> sort_and_merge(std::vector<Vec2d> points, double eps) {
  std::sort(points.begin(), points.end(), lex_less);
  std::vector<Vec2d> kept;
  kept.reserve(points.size());
  for (const Vec2d& p : points) {
    bool duplicate = false;
    for (std::size_t k = kept.size(); k-- > 0 && kept[k].x >= p.x - eps;) {
      if (distance(kept[k], p) < eps) {
        duplicate = true;
        break;
      }
    }
    if (!duplicate) kept.push_back(p);
  }
  return kept;
}

// True when some point of `sorted` (sorted by x) is closer than eps to p.
bool near_any(const std::vector<Vec2d>& sorted, const Vec2d& p, double eps) {
  auto it = std::lower_bound(sorted.begin(), sorted.end(), p.x - eps,
                             [](const Vec2d& q, double x) { return q.x < x; });
  for (; it != sorted.end() && it->x <= p.x + eps; ++it)
    if (distance(*it, p) < eps) return true;
  return false;
}

// A closed piece of a line: m + u d for u in [u0, u1], d of unit length (u is a
// distance); u0 = -inf and/or u1 = +inf for rays and lines.
struct LinePiece {
  Vec2d m, d;
  double u0 = 0, u1 = 0;
};

// Appends the points where `piece` meets the boundary of `rect`, each side
// taken as a closed segment with fixed coordinate `axis`. Sides parallel to
// the piece are skipped: an overlap along a side ends at Voronoi vertices
// (found as vertices) or at corners (found on the perpendicular sides).
void meet_boundary(const LinePiece& piece, const Rect2d& rect, double eps, std::vector<Vec2d>& out) {
  for (int axis = 0; axis < 2; ++axis) {
    const int other = 1 - axis;
    const double d_axis = coord(piece.d, axis);
    if (d_axis == 0) continue;
    const double sides[2] = {coord(rect.lo, axis), coord(rect.hi, axis)};
    const int side_count = sides[0] == sides[1] ? 1 : 2;
    for (int k = 0; k < side_count; ++k) {
      const double u = (sides[k] - coord(piece.m, axis)) / d_axis;
      if (!(u >= piece.u0 - eps && u <= piece.u1 + eps)) continue;
      const double lo = coord(rect.lo, other), hi = coord(rect.hi, other);
      const double along = coord(piece.m, other) + u * coord(piece.d, other);
      if (!(along >= lo - eps && along <= hi + eps)) continue;
      const double clamped = std::clamp(along, lo, hi);
      out.push_back(axis == 0 ? Vec2d{sides[k], clamped} : Vec2d{clamped, sides[k]});
    }
  }
}

// The piece m + u * direction / |direction|, u in [u0, u1]; false when the
// direction is zero or anything is non-finite (an overflowed construction).
bool piece_from(const Vec2d& m, const Vec2d& direction, double u0, double u1, LinePiece& piece) {
  const double len = std::hypot(direction.x, direction.y);
  if (!(len > 0) || !std::isfinite(len) || !finite(m)) return false;
  piece = {m, {direction.x / len, direction.y / len}, u0, u1};
  return true;
}

// The perpendicular bisector of p and q (p != q) as a full line.
bool bisector_line(const Vec2d& p, const Vec2d& q, LinePiece& piece) {
  return piece_from({0.5 * (p.x + q.x), 0.5 * (p.y + q.y)}, {-(q.y - p.y), q.x - p.x}, -kInf, kInf, piece);
}

Vec2d to_vec(const Kernel::Point_2& p) { return {CGAL::to_double(p.x()), CGAL::to_double(p.y())}; }

}  // namespace

std::vector<Vec2d> voronoi_candidates(const std::vector<Vec2d>& samples, const Rect2d& rect) {
  if (!finite(rect.lo) || !finite(rect.hi))
    throw std::invalid_argument("voronoi_candidates: rectangle has non-finite coordinates");
  if (rect.lo.x > rect.hi.x || rect.lo.y > rect.hi.y)
    throw std::invalid_argument("voronoi_candidates: rectangle has lo > hi");
  for (const Vec2d& s : samples)
    if (!finite(s)) throw std::invalid_argument("voronoi_candidates: sample has non-finite coordinates");

  const double eps = 1e-9 * (distance(rect.lo, rect.hi) + 1);
  std::vector<Vec2d> all_samples = samples;
  std::sort(all_samples.begin(), all_samples.end(), lex_less);
  const std::vector<Vec2d> sites = sort_and_merge(samples, eps);

  // Drops candidates near samples and near each other; sorts.
  auto finish = [&](const std::vector<Vec2d>& raw) {
    std::vector<Vec2d> out;
    for (const Vec2d& c : sort_and_merge(raw, eps))
      if (!near_any(all_samples, c, eps)) out.push_back(c);
    return out;
  };

  if (sites.empty()) return {{0.5 * (rect.lo.x + rect.hi.x), 0.5 * (rect.lo.y + rect.hi.y)}};
  if (rect.lo == rect.hi) return finish({rect.lo});
  if (sites.size() == 1) return finish({rect.lo, {rect.hi.x, rect.lo.y}, {rect.lo.x, rect.hi.y}, rect.hi});

  std::vector<Vec2d> raw;
  const bool segment_rect = rect.lo.x == rect.hi.x || rect.lo.y == rect.hi.y;
  if (segment_rect) {  // its end points are part of its (1D) boundary
    raw.push_back(rect.lo);
    raw.push_back(rect.hi);
  }
  auto add_vertex = [&](const Vec2d& v) {
    if (!finite(v)) return;
    if (v.x < rect.lo.x - eps || v.x > rect.hi.x + eps || v.y < rect.lo.y - eps || v.y > rect.hi.y + eps)
      return;
    raw.push_back({std::clamp(v.x, rect.lo.x, rect.hi.x), std::clamp(v.y, rect.lo.y, rect.hi.y)});
  };

  // Inserted one by one in sorted order so the triangulation (and so every
  // constructed coordinate) does not depend on the caller's order.
  Delaunay dt;
  Delaunay::Vertex_handle hint;
  for (const Vec2d& s : sites) {
    hint = dt.insert(Kernel::Point_2(s.x, s.y),
                     hint == Delaunay::Vertex_handle() ? Delaunay::Face_handle() : hint->face());
  }

  LinePiece piece;
  if (dt.dimension() < 2) {
    // Collinear: sorted by x then y is the order along the line.
    for (std::size_t i = 0; i + 1 < sites.size(); ++i)
      if (bisector_line(sites[i], sites[i + 1], piece)) meet_boundary(piece, rect, eps, raw);
    return finish(raw);
  }

  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) add_vertex(to_vec(dt.dual(f)));
  auto to_direction = [](const Kernel::Vector_2& v) -> Vec2d {
    return {CGAL::to_double(v.x()), CGAL::to_double(v.y())};
  };
  for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
    const CGAL::Object dual = dt.dual(*e);
    bool ok = false;
    if (const auto* seg = CGAL::object_cast<Kernel::Segment_2>(&dual)) {
      // Zero length (cocircular sites): a vertex, added above.
      const Vec2d a = to_vec(seg->source()), b = to_vec(seg->target());
      ok = piece_from(a, {b.x - a.x, b.y - a.y}, 0, distance(a, b), piece);
    } else if (const auto* ray = CGAL::object_cast<Kernel::Ray_2>(&dual)) {
      ok = piece_from(to_vec(ray->source()), to_direction(ray->to_vector()), 0, kInf, piece);
    } else if (const auto* line = CGAL::object_cast<Kernel::Line_2>(&dual)) {
      ok = piece_from(to_vec(line->point(0)), to_direction(line->to_vector()), -kInf, kInf, piece);
    }
    if (ok) meet_boundary(piece, rect, eps, raw);
  }
  return finish(raw);
}

std::vector<Vec3d> next_view_candidates(const Box3d& nav, std::span<const Vec3d> eyes) {
  const Vec3d e = nav.extent();
  int flat = -1;
  for (int a = 2; a >= 0; --a)
    if (e[a] <= 1e-9 * (e.x + e.y + e.z + 1)) flat = a;
  std::vector<Vec3d> out;
  if (flat >= 0) {
    const int u = flat == 0 ? 1 : 0, v = flat == 2 ? 1 : 2;
    std::vector<Vec2d> points;
    for (const Vec3d& eye : eyes) points.push_back({eye[u], eye[v]});
    for (const Vec2d& c : voronoi_candidates(points, {{nav.lo[u], nav.lo[v]}, {nav.hi[u], nav.hi[v]}})) {
      Vec3d p = nav.center();
      p[u] = c.x;
      p[v] = c.y;
      out.push_back(p);
    }
    return out;
  }
  for (int k = 0; k < 27; ++k) {
    const double f[3] = {0.5 * (k % 3), 0.5 * (k / 3 % 3), 0.5 * (k / 9)};
    const Vec3d p{nav.lo.x + f[0] * e.x, nav.lo.y + f[1] * e.y, nav.lo.z + f[2] * e.z};
    bool taken = false;
    for (const Vec3d& eye : eyes) taken = taken || eye == p;
    if (!taken) out.push_back(p);
  }
  return out;
}

}  // namespace cellbake
