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
//    relative depth bound gets its worst vertex inserted, until none does. A
//    world-space plane is an exact plane in (x, y, 1/z), so flat surfaces end
//    as a few large triangles. A violation on a straightened outline segment
//    re-inserts that segment's farthest staircase point instead.
// Each triangle belongs to the region that holds most of its triangulation
// component (the cells bounded by constraints) and takes, at every corner, the
// dense vertex of that region there (the pixel in the triangle's direction
// where the region meets itself across a skin), so the two sides of a
// silhouette use their own depths on one shared screen-space line.
#include "stages/simplify.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "stages/simplify_border.h"
#include "stages/simplify_grid.h"
#include "stages/simplify_outline.h"

namespace cellbake {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
struct FaceInfo {
  int label = INT_MIN;
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

class TinSimplifier {
 public:
  TinSimplifier(const FaceGrid& g, const FaceRegions& regions, FaceOutlines outlines,
                const std::vector<FixedSegment>& fixed, double eps)
      : g_(g), regions_(regions), outlines_(std::move(outlines)), fixed_(fixed), n_(g.size), eps_(eps),
        steiner_flag_(std::size_t(n_ + 1) * (n_ + 1), 0) {}

  std::vector<std::uint32_t> run() {
    for (;;) {
      build();
      bool rebuild = false;
      for (;;) {
        std::vector<LatticePoint> inserts;
        std::vector<ConstraintOwner> refines;
        evaluate(inserts, refines);
        if (!refines.empty()) {
          std::vector<ChainSegment> segments;
          for (const ConstraintOwner& o : refines) segments.push_back({o.chain, o.i, o.j});
          if (refine_outline_segments(outlines_, segments, fixed_, n_)) {
            for (const LatticePoint& p : inserts) add_steiner(p);
            rebuild = true;
            break;
          }
        }
        if (inserts.empty()) break;
        // Only faces around the new vertices change (Delaunay flips stay
        // around the inserted point); they inherit the region of the face
        // the point fell in.
        std::vector<Cdt::Vertex_handle> added;
        for (const LatticePoint& p : inserts) {
          add_steiner(p);
          if (const Cdt::Vertex_handle v = insert_steiner(p); v != Cdt::Vertex_handle()) added.push_back(v);
        }
        pending_.clear();
        for (const Cdt::Vertex_handle& v : added) {
          auto f = cdt_.incident_faces(v), end = f;
          do {
            if (!cdt_.is_infinite(f)) pending_.push_back(f);
          } while (++f != end);
        }
        std::sort(pending_.begin(), pending_.end());
        pending_.erase(std::unique(pending_.begin(), pending_.end()), pending_.end());
      }
      if (!rebuild) break;
    }
    return emit();
  }

 private:
  std::size_t lattice_index(int x, int y) const { return std::size_t(y) * (n_ + 1) + x; }
  static std::uint64_t key(std::size_t a, std::size_t b) {
    return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
  }
  static LatticePoint lattice_of(const CdtPoint& p) { return {int(std::lround(p.x())), int(std::lround(p.y()))}; }
  int label(int i, int j) const { return regions_.label[std::size_t(j) * n_ + i]; }

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

  void build() {
    cdt_.clear();
    owners_.clear();
    for (const FixedSegment& s : fixed_) {
      cdt_.insert_constraint(CdtPoint(s.a.x, s.a.y), CdtPoint(s.b.x, s.b.y));
      owners_[key(lattice_index(s.a.x, s.a.y), lattice_index(s.b.x, s.b.y))] = {};
    }
    for (std::size_t c = 0; c < outlines_.chains.size(); ++c) {
      const OutlineChain& ch = outlines_.chains[c];
      std::size_t prev = 0;
      for (std::size_t k = 1; k < ch.points.size(); ++k)
        if (ch.kept[k]) {
          const LatticePoint a = ch.points[prev], b = ch.points[k];
          if (!(a == b)) {
            cdt_.insert_constraint(CdtPoint(a.x, a.y), CdtPoint(b.x, b.y));
            owners_[key(lattice_index(a.x, a.y), lattice_index(b.x, b.y))] = {int(c), int(prev), int(k)};
          }
          prev = k;
        }
    }
    for (const LatticePoint& p : steiner_) insert_steiner(p);
    label_components();
    pending_.clear();
    for (auto f = cdt_.finite_faces_begin(); f != cdt_.finite_faces_end(); ++f) pending_.push_back(f);
  }

  // Components of finite faces joined across unconstrained edges; each takes
  // the region label holding most of its area (by the pixel under each
  // triangle's centroid), -1 for background.
  void label_components() {
    for (auto f = cdt_.all_faces_begin(); f != cdt_.all_faces_end(); ++f) f->info().label = INT_MIN;
    std::vector<Cdt::Face_handle> stack, members;
    std::vector<std::pair<int, double>> votes;
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
        const LatticePoint a = lattice_of(f->vertex(0)->point()), b = lattice_of(f->vertex(1)->point()),
                           c = lattice_of(f->vertex(2)->point());
        const double area = std::abs(double(b.x - a.x) * (c.y - a.y) - double(b.y - a.y) * (c.x - a.x));
        const int px = std::clamp(int(std::floor((a.x + b.x + c.x) / 3.0)), 0, n_ - 1);
        const int py = std::clamp(int(std::floor((a.y + b.y + c.y) / 3.0)), 0, n_ - 1);
        const int l = label(px, py);
        auto it = std::find_if(votes.begin(), votes.end(), [&](const auto& v) { return v.first == l; });
        if (it == votes.end()) votes.push_back({l, area});
        else it->second += area;
        for (int e = 0; e < 3; ++e) {
          const Cdt::Face_handle nb = f->neighbor(e);
          if (cdt_.is_infinite(nb) || cdt_.is_constrained({f, e}) || nb->info().label != INT_MIN) continue;
          nb->info().label = INT_MIN + 1;
          stack.push_back(nb);
        }
      }
      int best = -1;
      double best_area = -1;
      for (const auto& [l, area] : votes)
        if (area > best_area) best = l, best_area = area;
      for (const Cdt::Face_handle& f : members) f->info().label = best;
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
        const auto it = owners_.find(key(lattice_index(p.x, p.y), lattice_index(q.x, q.y)));
        if (it != owners_.end() && it->second.chain >= 0) {
          const OutlineChain& c = outlines_.chains[it->second.chain];
          const LatticePoint next = c.points[it->second.i] == p ? c.points[it->second.i + 1] : c.points[it->second.j - 1];
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

  void evaluate(std::vector<LatticePoint>& inserts, std::vector<ConstraintOwner>& refines) {
    std::array<LatticePoint, 3> p;
    std::array<std::uint32_t, 3> v;
    for (const Cdt::Face_handle& f : pending_) {
      const int l = f->info().label;
      if (l < 0 || !corners(f, p, v)) continue;
      const double w0 = g_.w[v[0]], w1 = g_.w[v[1]], w2 = g_.w[v[2]];
      const double x0 = p[0].x, y0 = p[0].y;
      const double orient = double(p[1].x - p[0].x) * (p[2].y - p[0].y) - double(p[1].y - p[0].y) * (p[2].x - p[0].x);
      if (orient == 0) continue;
      const double alpha = ((w1 - w0) * (p[2].y - y0) - (w2 - w0) * (p[1].y - y0)) / orient;
      const double beta = ((w2 - w0) * (p[1].x - x0) - (w1 - w0) * (p[2].x - x0)) / orient;
      const double gamma = w0 - alpha * x0 - beta * y0;
      const double cx = (p[0].x + p[1].x + p[2].x) / 3.0, cy = (p[0].y + p[1].y + p[2].y) / 3.0;
      double worst_free = eps_, worst_bound = eps_;
      LatticePoint free_at{-1, -1};
      ConstraintOwner bound_owner;
      bool bound_found = false;
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
        for (int x = int(std::ceil(xl - 1e-9)); x <= int(std::floor(xr + 1e-9)); ++x) {
          const LatticePoint q{x, y};
          if (q == p[0] || q == p[1] || q == p[2]) continue;
          // Outline points too: a straightened outline must not bridge a skin
          // (where the region meets itself there, the side the triangle is on).
          const bool outline = outlines_.on_outline[lattice_index(x, y)] != 0;
          const std::uint32_t dv = outline ? pick_vertex(l, q, cx, cy) : pick_vertex(l, q, x, y);
          if (dv == kNoVertex) continue;
          const double wp = alpha * x + beta * y + gamma;
          const double err = wp > 0 ? std::abs(g_.w[dv] - wp) / wp : 1e300;
          if (err <= eps_) continue;
          // On a constrained edge of this triangle?
          int edge = -1;
          for (int e = 0; e < 3 && edge < 0; ++e) {
            const LatticePoint a = p[(e + 1) % 3], b = p[(e + 2) % 3];
            const long o = long(b.x - a.x) * (q.y - a.y) - long(b.y - a.y) * (q.x - a.x);
            if (o == 0 && cdt_.is_constrained({f, e})) edge = e;
          }
          if (edge < 0) {
            if (err > worst_free && (!outline || unique_vertex(l, q))) worst_free = err, free_at = q;
          } else if (err > worst_bound) {
            const LatticePoint a = p[(edge + 1) % 3], b = p[(edge + 2) % 3];
            const auto it = owners_.find(key(lattice_index(a.x, a.y), lattice_index(b.x, b.y)));
            if (it != owners_.end() && it->second.chain >= 0) {
              worst_bound = err;
              bound_owner = it->second;
              bound_found = true;
            }
          }
        }
      }
      if (free_at.x >= 0) inserts.push_back(free_at);
      if (bound_found) refines.push_back(bound_owner);
    }
    std::sort(inserts.begin(), inserts.end(), [](const LatticePoint& a, const LatticePoint& b) {
      return a.y != b.y ? a.y < b.y : a.x < b.x;
    });
    inserts.erase(std::unique(inserts.begin(), inserts.end()), inserts.end());
    std::sort(refines.begin(), refines.end(), [](const ConstraintOwner& a, const ConstraintOwner& b) {
      return std::tie(a.chain, a.i, a.j) < std::tie(b.chain, b.i, b.j);
    });
    refines.erase(std::unique(refines.begin(), refines.end(),
                              [](const ConstraintOwner& a, const ConstraintOwner& b) {
                                return a.chain == b.chain && a.i == b.i && a.j == b.j;
                              }),
                  refines.end());
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
  std::vector<std::uint8_t> steiner_flag_;
  std::vector<LatticePoint> steiner_;
  Cdt cdt_;
  std::vector<Cdt::Face_handle> pending_;  // faces to evaluate next
  std::unordered_map<std::uint64_t, ConstraintOwner> owners_;
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

SimplifyResult simplify_face_mesh(const FaceMesh& in, int face_size, const SimplifyParams& params) {
  if (!(params.depth_error_relative >= 0))
    throw std::invalid_argument("simplify_face_mesh: depth_error_relative must be >= 0");
  if (!(params.boundary_error_px >= 0))
    throw std::invalid_argument("simplify_face_mesh: boundary_error_px must be >= 0");
  const FaceGrid grid = read_face_grid(in, face_size);
  SimplifyResult result;
  result.triangles_in = in.triangle_count();
  double eps = params.depth_error_relative;
  std::vector<std::uint32_t> tris;
  if (face_size < 4) {
    tris = dense_triangles(in);  // too small to simplify
  } else {
    const FaceRegions regions = label_face_regions(grid);
    std::vector<FixedSegment> fixed;
    for (const BorderPiece& p : split_face_border(in, grid, params.depth_error_relative)) {
      if (!p.covered) continue;
      const auto a = border_point(p.side, p.a, face_size), b = border_point(p.side, p.b, face_size);
      fixed.push_back({{a[0], a[1]}, {b[0], b[1]}});
    }
    const FaceOutlines traced = trace_face_outlines(grid, regions);
    auto simplify_with = [&](double depth_error) {
      FaceOutlines outlines = traced;
      straighten_face_outlines(outlines, fixed, params.boundary_error_px, depth_error, face_size);
      return TinSimplifier(grid, regions, std::move(outlines), fixed, depth_error).run();
    };
    tris = simplify_with(eps);
    for (int attempt = 0; tris.size() / 3 > params.max_triangles && attempt < params.max_relaxations; ++attempt) {
      const double looser = eps > 0 ? eps * 2 : 1e-3;
      std::vector<std::uint32_t> next = simplify_with(looser);
      // When relaxing the depth bound no longer pays (< 5 % fewer triangles), keep the tighter mesh.
      if (next.size() * 20 > tris.size() * 19) break;
      tris = std::move(next);
      eps = looser;
    }
  }
  result.mesh = compact(in, tris);
  result.triangles_out = result.mesh.triangle_count();
  result.depth_error_bound_used = eps;
  result.cap_forced_larger_error = eps > params.depth_error_relative;
  result.achieved = measure_simplification_error(in, result.mesh, face_size);
  return result;
}

}  // namespace cellbake
