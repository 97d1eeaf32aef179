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

// Whether the square of half-size h centred at (cx, cy) lies at least partly
// on the triangle's side of edge e (p = t[e], q = t[e + 1], third vertex r);
// true for a degenerate edge. For fixed cy this is monotone in cx (every
// floating-point step below is), so along a row it holds on a half-line.
bool square_meets_edge_side(const std::array<P2, 3>& t, int e, double cx, double cy, double h) {
  const P2& p = t[std::size_t(e)];
  const P2& q = t[std::size_t((e + 1) % 3)];
  const P2& r = t[std::size_t((e + 2) % 3)];
  const double nx = q.y - p.y, ny = p.x - q.x;  // edge normal
  if (nx == 0 && ny == 0) return true;
  const double side = nx * (r.x - p.x) + ny * (r.y - p.y);  // where the third vertex lies
  // The square's extent along the normal, relative to the edge line.
  const double centre = nx * (cx - p.x) + ny * (cy - p.y), reach = h * (std::abs(nx) + std::abs(ny));
  return side >= 0 ? !(centre + reach < 0) : !(centre - reach > 0);
}

// True when the triangle and the square [cx - h, cx + h] x [cy - h, cy + h]
// overlap (touching counts). The square's axes are tested by the caller
// (bounding box).
bool triangle_overlaps_square(const std::array<P2, 3>& t, double cx, double cy, double h) {
  for (int e = 0; e < 3; ++e)
    if (!square_meets_edge_side(t, e, cx, cy, h)) return false;
  return true;
}

// Narrows [lo, hi] (texel columns of row y) to those whose square meets the
// triangle's side of edge e: the exact answers of square_meets_edge_side,
// found from an estimate of where the half-line starts and a few exact tests
// (the test is monotone along the row).
void clip_row_to_edge(const std::array<P2, 3>& t, int e, int y, double h, int& lo, int& hi) {
  const P2& p = t[std::size_t(e)];
  const P2& q = t[std::size_t((e + 1) % 3)];
  const P2& r = t[std::size_t((e + 2) % 3)];
  const double nx = q.y - p.y, ny = p.x - q.x;
  const double cy = y + 0.5;
  const auto holds = [&](int x) { return square_meets_edge_side(t, e, x + 0.5, cy, h); };
  if (nx == 0) {  // the same answer along the whole row
    if (!holds(lo)) hi = lo - 1;
    return;
  }
  const double side = nx * (r.x - p.x) + ny * (r.y - p.y);
  const double reach = h * (std::abs(nx) + std::abs(ny));
  // Where centre -+ reach crosses 0 along the row, as a column.
  const double cross = p.x + (-(ny * (cy - p.y)) + (side >= 0 ? -reach : reach)) / nx - 0.5;
  // Holds for x >= boundary when the test grows with x, else for x <= boundary.
  const bool holds_right = (nx > 0) == (side >= 0);
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
    const bool finite = std::isfinite(lo_x) && std::isfinite(hi_x) && std::isfinite(lo_y) && std::isfinite(hi_y);
    for (int y = y0; y <= y1; ++y) {
      int lo = x0, hi = x1;
      if (finite)  // the texels of the row that pass all three edges: one run
        for (int e = 0; e < 3 && lo <= hi; ++e) clip_row_to_edge(p, e, y, h, lo, hi);
      for (int x = lo; x <= hi; ++x) {
        std::uint8_t& r = read[std::size_t(y) * std::size_t(size) + std::size_t(x)];
        if (!r && (finite || triangle_overlaps_square(p, x + 0.5, y + 0.5, h))) r = 1;
      }
    }
  }
  return read;
}

}  // namespace cellbake
