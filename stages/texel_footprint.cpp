// Texels a bilinearly filtered triangle reads: a 2D separating-axis test of
// each triangle against the square of half-size 1 pixel around each texel
// centre in its bounding box (Akenine-Möller 2001, "Fast 3D triangle-box
// overlap testing", reduced to two dimensions).
#include "stages/texel_footprint.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

struct P2 {
  double x, y;
};

// Edge e of triangle t (from t[e] to t[e + 1], third vertex t[e + 2]) as a
// test of squares of half-size h: whether a square lies at least partly on the
// triangle's side of the edge line (always, for a degenerate edge). For a
// fixed centre row the test is monotone in the centre column (every
// floating-point step of meets() is), so along a row it holds on a half-line.
struct EdgeSide {
  P2 p;
  double nx, ny;     // edge normal
  double reach;      // the square's extent along the normal
  bool positive;     // the third vertex lies on the normal's side
  bool degenerate;

  EdgeSide(const std::array<P2, 3>& t, int e, double h) : p(t[std::size_t(e)]) {
    const P2& q = t[std::size_t((e + 1) % 3)];
    const P2& r = t[std::size_t((e + 2) % 3)];
    nx = q.y - p.y, ny = p.x - q.x;
    degenerate = nx == 0 && ny == 0;
    positive = nx * (r.x - p.x) + ny * (r.y - p.y) >= 0;
    reach = h * (std::abs(nx) + std::abs(ny));
  }

  bool meets(double cx, double cy) const {
    if (degenerate) return true;
    const double centre = nx * (cx - p.x) + ny * (cy - p.y);  // relative to the edge line
    return positive ? !(centre + reach < 0) : !(centre - reach > 0);
  }
};

// Narrows [lo, hi] (texel columns of row y) to those whose square meets the
// edge's side: the exact answers of EdgeSide::meets, found from an estimate of
// where the half-line starts and a few exact tests (meets is monotone along
// the row).
void clip_row_to_edge(const EdgeSide& edge, int y, int& lo, int& hi) {
  const double cy = y + 0.5;
  const auto holds = [&](int x) { return edge.meets(x + 0.5, cy); };
  if (edge.nx == 0) {  // the same answer along the whole row
    if (!holds(lo)) hi = lo - 1;
    return;
  }
  // Where centre -+ reach crosses 0 along the row, as a column.
  const double cross =
      edge.p.x + (-(edge.ny * (cy - edge.p.y)) + (edge.positive ? -edge.reach : edge.reach)) / edge.nx - 0.5;
  // Holds for x >= boundary when the test grows with x, else for x <= boundary.
  const bool holds_right = (edge.nx > 0) == edge.positive;
  const double clamped = std::fmin(std::fmax(cross, double(lo) - 1), double(hi) + 1);
  int k = int(std::floor(clamped));
  if (holds_right) {  // first column that holds: lo..hi + 1
    k = std::max(k, lo);
    while (k > lo && holds(k - 1)) --k;
    while (k <= hi && !holds(k)) ++k;
    lo = k;
  } else {  // last column that holds: lo - 1..hi
    k = std::min(k + 1, hi);
    while (k < hi && holds(k + 1)) ++k;
    while (k >= lo && !holds(k)) --k;
    hi = k;
  }
}

}  // namespace

std::vector<std::uint8_t> texels_read_by(const FaceMesh& mesh, int size) {
  if (size < 1) throw std::invalid_argument("texels_read_by: image size " + std::to_string(size));
  std::vector<std::uint8_t> read(std::size_t(size) * std::size_t(size), 0);
  const double h = 1.0 + 1e-6;  // a texel centre within one pixel on both axes (rounding: read)
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::array<P2, 3> p;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t i = mesh.indices[3 * t + std::size_t(c)];
      if (i >= mesh.uvs.size()) throw std::invalid_argument("texels_read_by: index out of range");
      p[std::size_t(c)] = {double(mesh.uvs[i].u) * size, double(mesh.uvs[i].v) * size};
    }
    const double lo_x = std::min({p[0].x, p[1].x, p[2].x}), hi_x = std::max({p[0].x, p[1].x, p[2].x});
    const double lo_y = std::min({p[0].y, p[1].y, p[2].y}), hi_y = std::max({p[0].y, p[1].y, p[2].y});
    // Texels whose centre i + 0.5 lies within h of the bounding box.
    const auto first = [&](double lo) { return std::max(0, int(std::ceil(lo - h - 0.5))); };
    const auto last = [&](double hi) { return std::min(size - 1, int(std::floor(hi + h - 0.5))); };
    const int x0 = first(lo_x), x1 = last(hi_x), y0 = first(lo_y), y1 = last(hi_y);
    // A texel is read when its square meets the triangle (touching counts):
    // the bounding box above, and each edge's side (2D separating axes).
    const std::array<EdgeSide, 3> edges{EdgeSide(p, 0, h), EdgeSide(p, 1, h), EdgeSide(p, 2, h)};
    const bool finite = std::isfinite(lo_x) && std::isfinite(hi_x) && std::isfinite(lo_y) && std::isfinite(hi_y);
    for (int y = y0; y <= y1; ++y) {
      int lo = x0, hi = x1;
      if (finite)  // the texels of the row that pass all three edges: one run
        for (int e = 0; e < 3 && lo <= hi; ++e) clip_row_to_edge(edges[std::size_t(e)], y, lo, hi);
      for (int x = lo; x <= hi; ++x) {
        std::uint8_t& r = read[std::size_t(y) * std::size_t(size) + std::size_t(x)];
        if (r) continue;
        bool meets = true;
        for (int e = 0; e < 3 && meets && !finite; ++e) meets = edges[std::size_t(e)].meets(x + 0.5, y + 0.5);
        if (meets) r = 1;
      }
    }
  }
  return read;
}

}  // namespace cellbake
