// Face-border rule of the simplifier (see simplify_border.h).
#include "stages/simplify/simplify_border.h"

#include <algorithm>
#include <cmath>

namespace cellbake {
namespace {

using Point = std::array<int, 2>;

Vec3d to_d(Vec3f p) { return {p.x, p.y, p.z}; }

class BorderRule {
 public:
  BorderRule(const FaceMesh& in, const FaceGrid& g, double eps) : in_(in), g_(g), n_(g.size), eps_(eps) {}

  std::vector<BorderPiece> run() {
    for (int side = 0; side < 4; ++side) split(side, 0, n_);
    return std::move(pieces_);
  }

 private:
  Point lattice(int side, int t, int d) const {
    switch (side) {
      case 0: return {t, d};
      case 1: return {t, n_ - d};
      case 2: return {d, t};
      default: return {n_ - d, t};
    }
  }
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

  bool clean(int side, int t) const {
    const Point p = side_pixel(side, t - 1, 0), q = side_pixel(side, t, 0);
    if (!covered(p) || !covered(q)) return false;
    const Point b = lattice(side, t, 0), i = lattice(side, t, 1);
    return vertex(p, b) == vertex(q, b) && vertex(p, i) == vertex(q, i);
  }

  std::uint32_t border_vertex(int side, int a, int b, int t) const {
    return vertex(side_pixel(side, std::clamp(t, a, b - 1), 0), lattice(side, t, 0));
  }

  bool mergeable(int side, int a, int b) const {
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
      if (!(std::abs(lambda - 1.0) <= eps_)) return false;
    }
    return true;
  }

  void split(int side, int a, int b) {
    const int len = b - a;
    if (len == 1 || mergeable(side, a, b)) {
      pieces_.push_back({side, a, b, len > 1 || covered(side_pixel(side, a, 0))});
      return;
    }
    if (len % 2 == 0) {
      split(side, a, a + len / 2);
      split(side, a + len / 2, b);
    } else {
      const int h = (len - 1) / 2;
      split(side, a, a + h);
      split(side, a + h, a + h + 1);
      split(side, a + h + 1, b);
    }
  }

  const FaceMesh& in_;
  const FaceGrid& g_;
  int n_;
  double eps_;
  std::vector<BorderPiece> pieces_;
};

}  // namespace

std::vector<BorderPiece> split_face_border(const FaceMesh& in, const FaceGrid& g, double depth_error_relative) {
  return BorderRule(in, g, depth_error_relative).run();
}

std::uint32_t border_piece_vertex(const FaceGrid& g, const BorderPiece& p, int t) {
  const int n = g.size;
  const int a = std::clamp(t, p.a, p.b - 1);
  Point pixel;
  switch (p.side) {
    case 0: pixel = {a, 0}; break;
    case 1: pixel = {a, n - 1}; break;
    case 2: pixel = {0, a}; break;
    default: pixel = {n - 1, a}; break;
  }
  const Point c = border_point(p.side, t, n);
  return g.vertex(pixel[0], pixel[1], c[0], c[1]);
}

}  // namespace cellbake
