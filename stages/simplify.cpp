// Grid-aware simplification of dense face meshes (see simplify.h for the
// contract; Wilson 2002 ch. 5 §5.2.3 for the error model).
//
// Layout of one N x N face:
//  * Border rule. Each of the four border lines (lattice 0..N) is cut into
//    intervals by a fixed, reversal-symmetric recursive bisection. An interval
//    is one straight output edge when every lattice point on it is "clean"
//    (the two border pixels there share one vertex; build_depth_meshes makes
//    this true on both neighbouring faces or on neither) and the interior
//    vertices lie within depth_error_relative of the segment along their rays.
//    The test reads only positions both faces hold bit for bit and is symmetric
//    under swapping the ends, so both faces keep the same border vertices.
//  * Ring. The outermost ring of pixels is cut into four trapezoids (corner
//    pixels split along a diagonal); each border interval's share of the ring
//    is triangulated by zipping the interval's two border vertices to the kept
//    vertices on the lattice line one pixel inside.
//  * Inner region. A region quadtree over the remaining pixels merges a block
//    when its four children merged, all its pixels share one vertex per lattice
//    point (no skin inside), and all its vertices fit one least-squares plane in
//    (x, y, 1/z) within half the depth tolerance (so any triangle spanned by
//    block vertices stays within the tolerance). Leaves are triangulated as
//    convex polygons through every kept lattice point on their sides (T-junction
//    fans), so the output has no cracks and no flips.
//  * Whole face: when the entire face is clean and flat, it is one polygon
//    whose side vertices are the border rule's.
#include "stages/simplify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/simplify_grid.h"

namespace cellbake {
namespace {

struct Rect {
  int x0, y0, x1, y1;  // pixels [x0, x1) x [y0, y1)
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
};

struct Piece {
  int side, a, b;  // border interval [a, b] of `side`
};

struct ChainPoint {
  int t;            // coordinate along the chain's line
  std::uint32_t v;  // input vertex
};

Vec3d to_d(Vec3f p) { return {p.x, p.y, p.z}; }

class FaceSimplifier {
 public:
  FaceSimplifier(const FaceMesh& in, const FaceGrid& g, double border_eps, double eps)
      : in_(in), g_(g), n_(g.size), border_eps_(border_eps), eps_(eps), kept_(std::size_t(n_ + 1) * (n_ + 1), 0) {}

  std::vector<std::uint32_t> run() {
    if (n_ < 4) {
      for (int j = 0; j < n_; ++j)
        for (int i = 0; i < n_; ++i) emit_pixel(i, j);
      return std::move(out_);
    }
    for (int side = 0; side < 4; ++side) split_border(side, 0, n_);
    const Rect face{0, 0, n_, n_};
    if (clean_and_flat(face)) {
      for (const Piece& p : pieces_) {
        keep(lattice(p.side, p.a, 0));
        keep(lattice(p.side, p.b, 0));
      }
      emit_leaf(face);
      return std::move(out_);
    }
    for (const Piece& p : pieces_) force_inner_points(p);
    const Rect inner{1, 1, n_ - 1, n_ - 1};
    if (build(inner)) leaves_.push_back(inner);
    for (const Rect& r : leaves_) {
      keep({r.x0, r.y0});
      keep({r.x1, r.y0});
      keep({r.x0, r.y1});
      keep({r.x1, r.y1});
    }
    for (const Piece& p : pieces_) emit_piece(p);
    for (const Rect& r : leaves_) emit_leaf(r);
    return std::move(out_);
  }

 private:
  using Point = std::array<int, 2>;

  // --- sides: lattice point at coordinate t along side `side`, d pixels inside.
  Point lattice(int side, int t, int d) const {
    switch (side) {
      case 0: return {t, d};
      case 1: return {t, n_ - d};
      case 2: return {d, t};
      default: return {n_ - d, t};
    }
  }
  // Pixel between t = a and a + 1, d pixel rows inside the border.
  Point side_pixel(int side, int a, int d) const {
    switch (side) {
      case 0: return {a, d};
      case 1: return {a, n_ - 1 - d};
      case 2: return {d, a};
      default: return {n_ - 1 - d, a};
    }
  }
  bool covered(Point p) const { return g_.covered(p[0], p[1]); }
  std::uint32_t vertex(Point pixel, Point corner) const { return g_.vertex(pixel[0], pixel[1], corner[0], corner[1]); }
  void keep(Point c) { kept_[std::size_t(c[1]) * (n_ + 1) + c[0]] = 1; }
  bool is_kept(Point c) const { return kept_[std::size_t(c[1]) * (n_ + 1) + c[0]] != 0; }

  // Border point t (1 <= t <= N-1) is clean: both border pixels there are
  // covered and share their vertices on the border and one pixel inside.
  bool clean(int side, int t) const {
    const Point p = side_pixel(side, t - 1, 0), q = side_pixel(side, t, 0);
    if (!covered(p) || !covered(q)) return false;
    const Point b = lattice(side, t, 0), i = lattice(side, t, 1);
    return vertex(p, b) == vertex(q, b) && vertex(p, i) == vertex(q, i);
  }

  // Vertex of the interval [a, b] at border coordinate t (a <= t <= b).
  std::uint32_t border_vertex(int side, int a, int b, int t) const {
    return vertex(side_pixel(side, std::clamp(t, a, b - 1), 0), lattice(side, t, 0));
  }

  bool border_mergeable(int side, int a, int b) const {
    for (int t = std::max(a, 1); t <= std::min(b, n_ - 1); ++t)
      if (!clean(side, t)) return false;
    // Straightness along the rays: the removed vertex P_t moves to lambda P_t on
    // the segment; symmetric in (a, b) bit for bit (negations are exact).
    const Vec3d pa = to_d(in_.positions[border_vertex(side, a, b, a)]);
    const Vec3d pb = to_d(in_.positions[border_vertex(side, a, b, b)]);
    const Vec3d c1 = cross(pa, pb), d = pb - pa;
    for (int t = a + 1; t < b; ++t) {
      const Vec3d c2 = cross(to_d(in_.positions[border_vertex(side, a, b, t)]), d);
      const double den = dot(c2, c2);
      if (!(den > 0)) return false;
      const double lambda = dot(c1, c2) / den;
      if (!(std::abs(lambda - 1.0) <= border_eps_)) return false;
    }
    return true;
  }

  // Reversal-symmetric bisection: even lengths in halves, odd lengths as
  // (L-1)/2, 1, (L-1)/2.
  void split_border(int side, int a, int b) {
    const int len = b - a;
    if (len == 1 || border_mergeable(side, a, b)) {
      pieces_.push_back({side, a, b});
      return;
    }
    if (len % 2 == 0) {
      split_border(side, a, a + len / 2);
      split_border(side, a + len / 2, b);
    } else {
      const int h = (len - 1) / 2;
      split_border(side, a, a + h);
      split_border(side, a + h, a + h + 1);
      split_border(side, a + h + 1, b);
    }
  }

  bool piece_covered(const Piece& p) const { return p.b - p.a > 1 || covered(side_pixel(p.side, p.a, 0)); }

  // Top chain of a piece: kept points on the lattice line one pixel inside.
  std::vector<ChainPoint> top_chain(const Piece& p) const {
    const int ta = std::max(p.a, 1), tb = std::min(p.b, n_ - 1);
    std::vector<ChainPoint> chain;
    for (int t = ta; t <= tb; ++t) {
      const Point c = lattice(p.side, t, 1);
      if (t == ta || t == tb || is_kept(c))
        chain.push_back({t, vertex(side_pixel(p.side, std::clamp(t, p.a, p.b - 1), 0), c)});
    }
    return chain;
  }

  void force_inner_points(const Piece& p) {
    if (!piece_covered(p)) return;
    const int ta = std::max(p.a, 1), tb = std::min(p.b, n_ - 1);
    keep(lattice(p.side, ta, 1));
    keep(lattice(p.side, tb, 1));
    bool shared = true;
    for (int t = ta + 1; t < tb && shared; ++t) {
      const Point c = lattice(p.side, t, 1);
      const std::uint32_t v = vertex(side_pixel(p.side, t, 0), c);
      const Point r0 = side_pixel(p.side, t - 1, 1), r1 = side_pixel(p.side, t, 1);
      shared = covered(r0) && covered(r1) && vertex(r0, c) == v && vertex(r1, c) == v;
    }
    if (!shared)
      for (int t = ta; t <= tb; ++t) keep(lattice(p.side, t, 1));
  }

  // --- inner region quadtree.
  std::uint32_t rect_vertex(const Rect& r, int x, int y) const {
    const int px = std::min(x, r.x1 - 1), py = std::min(y, r.y1 - 1);
    return g_.vertex(px, py, x, y);
  }

  // All pixels touching lattice point (x, y) inside r use one vertex.
  bool lattice_point_clean(const Rect& r, int x, int y) const {
    std::uint32_t v = kNoVertex;
    for (int py = y - 1; py <= y; ++py)
      for (int px = x - 1; px <= x; ++px) {
        if (px < r.x0 || py < r.y0 || px >= r.x1 || py >= r.y1) continue;
        const std::uint32_t u = g_.vertex(px, py, x, y);
        if (v != kNoVertex && u != v) return false;
        v = u;
      }
    return true;
  }

  // Vertices of r fit one plane in (x, y, 1/z) within half the tolerance.
  bool flat(const Rect& r) const {
    double s1 = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, sw = 0, sxw = 0, syw = 0, w_min = 1e300;
    for (int y = r.y0; y <= r.y1; ++y)
      for (int x = r.x0; x <= r.x1; ++x) {
        const double w = g_.w[rect_vertex(r, x, y)];
        const double lx = x - r.x0, ly = y - r.y0;
        s1 += 1, sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, syy += ly * ly;
        sw += w, sxw += lx * w, syw += ly * w;
        w_min = std::min(w_min, w);
      }
    // Normal equations [sxx sxy sx; sxy syy sy; sx sy s1] (a b c) = (sxw syw sw), Cramer's rule.
    const double det = sxx * (syy * s1 - sy * sy) - sxy * (sxy * s1 - sy * sx) + sx * (sxy * sy - syy * sx);
    if (!(std::abs(det) > 0)) return false;
    const double a = (sxw * (syy * s1 - sy * sy) - sxy * (syw * s1 - sy * sw) + sx * (syw * sy - syy * sw)) / det;
    const double b = (sxx * (syw * s1 - sw * sy) - sxw * (sxy * s1 - sy * sx) + sx * (sxy * sw - syw * sx)) / det;
    const double c = (sxx * (syy * sw - sy * syw) - sxy * (sxy * sw - syw * sx) + sxw * (sxy * sy - syy * sx)) / det;
    const double tol = 0.5 * eps_ * w_min / (1.0 + eps_);
    for (int y = r.y0; y <= r.y1; ++y)
      for (int x = r.x0; x <= r.x1; ++x) {
        const double w = g_.w[rect_vertex(r, x, y)];
        if (!(std::abs(a * (x - r.x0) + b * (y - r.y0) + c - w) <= tol)) return false;
      }
    return true;
  }

  bool clean_and_flat(const Rect& r) const {
    for (int y = r.y0; y < r.y1; ++y)
      for (int x = r.x0; x < r.x1; ++x)
        if (!g_.covered(x, y)) return false;
    for (int y = r.y0; y <= r.y1; ++y)
      for (int x = r.x0; x <= r.x1; ++x)
        if (!lattice_point_clean(r, x, y)) return false;
    return flat(r);
  }

  // Returns whether r merges into one block; when it does not, its merged
  // children (and recursively their descendants) are recorded as leaves.
  bool build(const Rect& r) {
    if (r.width() <= 0 || r.height() <= 0) return false;
    if (r.width() == 1 && r.height() == 1) return g_.covered(r.x0, r.y0);
    const int xm = r.width() >= 2 ? r.x0 + r.width() / 2 : r.x1;
    const int ym = r.height() >= 2 ? r.y0 + r.height() / 2 : r.y1;
    std::array<Rect, 4> child{Rect{r.x0, r.y0, xm, ym}, Rect{xm, r.y0, r.x1, ym}, Rect{r.x0, ym, xm, r.y1},
                              Rect{xm, ym, r.x1, r.y1}};
    std::array<bool, 4> merged{};
    bool all = true;
    for (int k = 0; k < 4; ++k) {
      if (child[k].width() <= 0 || child[k].height() <= 0) {
        merged[k] = false;
        continue;  // empty child (a 1-wide rect split in one direction only)
      }
      merged[k] = build(child[k]);
      all = all && merged[k];
    }
    if (all) {
      bool seams = true;
      if (xm < r.x1)
        for (int y = r.y0; y <= r.y1 && seams; ++y) seams = lattice_point_clean(r, xm, y);
      if (ym < r.y1)
        for (int x = r.x0; x <= r.x1 && seams; ++x) seams = lattice_point_clean(r, x, ym);
      if (seams && flat(r)) return true;
    }
    for (int k = 0; k < 4; ++k)
      if (merged[k]) leaves_.push_back(child[k]);
    return false;
  }

  // --- emission.
  void emit(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    const long orient = long(g_.x[b] - g_.x[a]) * (g_.y[c] - g_.y[a]) - long(g_.y[b] - g_.y[a]) * (g_.x[c] - g_.x[a]);
    if (orient == 0) throw std::logic_error("simplify_face_mesh: produced a degenerate triangle");
    if ((orient > 0 ? 1 : -1) != g_.orientation) std::swap(b, c);
    out_.insert(out_.end(), {a, b, c});
  }

  void emit_pixel(int i, int j) {
    if (!g_.covered(i, j)) return;
    for (std::uint32_t t : g_.pixel_triangles[std::size_t(j) * n_ + i])
      out_.insert(out_.end(), {in_.indices[3 * t], in_.indices[3 * t + 1], in_.indices[3 * t + 2]});
  }

  // Triangulates the region between two chains on parallel lines, both ordered
  // by increasing t (any monotone merge is a valid triangulation).
  void zip(const std::vector<ChainPoint>& a, const std::vector<ChainPoint>& b) {
    std::size_t i = 0, j = 0;
    while (i + 1 < a.size() || j + 1 < b.size()) {
      const bool advance_a =
          j + 1 >= b.size() || (i + 1 < a.size() && a[i].t + a[i + 1].t <= b[j].t + b[j + 1].t);
      if (advance_a) {
        emit(a[i].v, b[j].v, a[i + 1].v);
        ++i;
      } else {
        emit(a[i].v, b[j].v, b[j + 1].v);
        ++j;
      }
    }
  }

  void emit_piece(const Piece& p) {
    if (!piece_covered(p)) return;
    const std::vector<ChainPoint> bottom{{p.a, border_vertex(p.side, p.a, p.b, p.a)},
                                         {p.b, border_vertex(p.side, p.a, p.b, p.b)}};
    zip(bottom, top_chain(p));
  }

  void emit_leaf(const Rect& r) {
    if (r.width() == 1 && r.height() == 1) {
      emit_pixel(r.x0, r.y0);
      return;
    }
    auto side_points = [&](int x0, int y0, int x1, int y1) {  // from (x0,y0) towards (x1,y1), end excluded
      std::vector<ChainPoint> pts;
      const int steps = std::max(std::abs(x1 - x0), std::abs(y1 - y0));
      const int dx = (x1 > x0) - (x1 < x0), dy = (y1 > y0) - (y1 < y0);
      for (int k = 0; k < steps; ++k) {
        const int x = x0 + k * dx, y = y0 + k * dy;
        if (k == 0 || is_kept({x, y})) pts.push_back({k, rect_vertex(r, x, y)});
      }
      return pts;
    };
    if (r.width() == 1 || r.height() == 1) {
      // Two long sides (both ends always included), zipped.
      auto line = [&](int x0, int y0, int dx, int dy, int steps) {
        std::vector<ChainPoint> pts;
        for (int k = 0; k <= steps; ++k) {
          const int x = x0 + k * dx, y = y0 + k * dy;
          if (k == 0 || k == steps || is_kept({x, y})) pts.push_back({k, rect_vertex(r, x, y)});
        }
        return pts;
      };
      if (r.width() == 1)
        zip(line(r.x0, r.y0, 0, 1, r.height()), line(r.x1, r.y0, 0, 1, r.height()));
      else
        zip(line(r.x0, r.y0, 1, 0, r.width()), line(r.x0, r.y1, 1, 0, r.width()));
      return;
    }
    const std::array<std::vector<ChainPoint>, 4> sides{side_points(r.x0, r.y0, r.x1, r.y0), side_points(r.x1, r.y0, r.x1, r.y1),
                                                       side_points(r.x1, r.y1, r.x0, r.y1), side_points(r.x0, r.y1, r.x0, r.y0)};
    std::vector<std::uint32_t> ring;
    std::array<std::size_t, 4> corner_at{};
    for (int s = 0; s < 4; ++s) {
      corner_at[s] = ring.size();
      for (const ChainPoint& p : sides[s]) ring.push_back(p.v);
    }
    const std::size_t m = ring.size();
    // Corner s sits between side s-1 (ending there) and side s (starting there).
    for (int s = 0; s < 4; ++s) {
      if (sides[s].size() == 1 && sides[(s + 3) % 4].size() == 1) {
        for (std::size_t k = 1; k + 1 < m; ++k)
          emit(ring[corner_at[s]], ring[(corner_at[s] + k) % m], ring[(corner_at[s] + k + 1) % m]);
        return;
      }
    }
    const std::uint32_t centre = rect_vertex(r, r.x0 + r.width() / 2, r.y0 + r.height() / 2);
    for (std::size_t k = 0; k < m; ++k) emit(centre, ring[k], ring[(k + 1) % m]);
  }

  const FaceMesh& in_;
  const FaceGrid& g_;
  int n_;
  double border_eps_, eps_;
  std::vector<std::uint8_t> kept_;
  std::vector<Piece> pieces_;
  std::vector<Rect> leaves_;
  std::vector<std::uint32_t> out_;
};

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
  const FaceGrid grid = read_face_grid(in, face_size);
  SimplifyResult result;
  result.triangles_in = in.triangle_count();
  double eps = params.depth_error_relative;
  std::vector<std::uint32_t> tris = FaceSimplifier(in, grid, params.depth_error_relative, eps).run();
  for (int attempt = 0; tris.size() / 3 > params.max_triangles && attempt < params.max_relaxations; ++attempt) {
    const double looser = eps > 0 ? eps * 2 : 1e-3;
    std::vector<std::uint32_t> next = FaceSimplifier(in, grid, params.depth_error_relative, looser).run();
    // Silhouettes and skins are never simplified: when relaxing the depth bound
    // no longer pays (< 5 % fewer triangles), keep the tighter mesh.
    if (next.size() * 20 > tris.size() * 19) break;
    tris = std::move(next);
    eps = looser;
  }
  result.mesh = compact(in, tris);
  result.triangles_out = result.mesh.triangle_count();
  result.depth_error_bound_used = eps;
  result.cap_forced_larger_error = eps > params.depth_error_relative;
  result.achieved = measure_simplification_error(in, result.mesh, face_size);
  return result;
}

}  // namespace cellbake
