// Error of a simplified face mesh against its dense grid (see simplify_error.h).
#include "stages/simplify_error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "stages/simplify_grid.h"

namespace cellbake {
namespace {

// Offsets chosen so that no segment between lattice points shorter than ~700 px
// passes exactly through a sample.
constexpr double kOffsetX = 0.0313, kOffsetY = 0.0711;

struct ScreenVertex {
  double x, y, w;
};

}  // namespace

SimplifyError measure_simplification_error(const FaceMesh& dense, const FaceMesh& simplified, int face_size) {
  const FaceGrid grid = read_face_grid(dense, face_size);
  const int n = face_size;
  std::vector<ScreenVertex> sv(simplified.positions.size());
  for (std::size_t v = 0; v < sv.size(); ++v) {
    const double x = double(simplified.uvs[v].u) * n, y = double(simplified.uvs[v].v) * n;
    sv[v] = {x, y, inverse_planar_depth(simplified.positions[v], x, y, n)};
  }
  SimplifyError err;
  // Per sample: how many simplified triangles cover it; its depth error.
  std::vector<std::uint8_t> hits(std::size_t(n) * n * 4, 0);
  std::vector<double> depth_error(std::size_t(n) * n * 4, 0.0);
  const std::size_t nt = simplified.indices.size() / 3;
  for (std::size_t t = 0; t < nt; ++t) {
    const ScreenVertex& a = sv[simplified.indices[3 * t]];
    const ScreenVertex& b = sv[simplified.indices[3 * t + 1]];
    const ScreenVertex& c = sv[simplified.indices[3 * t + 2]];
    const double orient = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (orient == 0 || (orient > 0 ? 1 : -1) != grid.orientation) ++err.flipped_triangles;
    if (orient == 0) continue;
    // Plane w = alpha x + beta y + gamma through the three vertices.
    const double alpha = ((b.w - a.w) * (c.y - a.y) - (c.w - a.w) * (b.y - a.y)) / orient;
    const double beta = ((c.w - a.w) * (b.x - a.x) - (b.w - a.w) * (c.x - a.x)) / orient;
    const double gamma = a.w - alpha * a.x - beta * a.y;
    const double ymin = std::min({a.y, b.y, c.y}), ymax = std::max({a.y, b.y, c.y});
    const int j0 = std::max(0, int(std::floor(ymin)) - 1), j1 = std::min(n - 1, int(std::ceil(ymax)));
    const std::array<const ScreenVertex*, 3> tri{&a, &b, &c};
    for (int j = j0; j <= j1; ++j)
      for (int dy = 0; dy < 2; ++dy) {
        const double y = dy ? j + 1 - kOffsetY : j + kOffsetY;
        if (y < ymin || y > ymax) continue;
        double xl = std::numeric_limits<double>::infinity(), xr = -xl;
        for (int e = 0; e < 3; ++e) {
          const ScreenVertex& p = *tri[e];
          const ScreenVertex& q = *tri[(e + 1) % 3];
          if ((p.y - y) * (q.y - y) > 0 || p.y == q.y) continue;
          const double x = p.x + (y - p.y) * (q.x - p.x) / (q.y - p.y);
          xl = std::min(xl, x);
          xr = std::max(xr, x);
        }
        if (!(xl <= xr)) continue;
        const int i0 = std::max(0, int(std::floor(xl)) - 1), i1 = std::min(n - 1, int(std::ceil(xr)));
        for (int i = i0; i <= i1; ++i)
          for (int dx = 0; dx < 2; ++dx) {
            const double x = dx ? i + 1 - kOffsetX : i + kOffsetX;
            if (x < xl - 1e-12 || x > xr + 1e-12) continue;
            const std::size_t s = (std::size_t(j) * n + i) * 4 + dy * 2 + dx;
            if (hits[s] < 255) ++hits[s];
            if (!grid.covered(i, j)) continue;
            const std::uint32_t v = grid.vertex(i, j, i + dx, j + dy);
            const double w_out = alpha * grid.x[v] + beta * grid.y[v] + gamma;
            const double e_rel = w_out > 0 ? std::abs(grid.w[v] - w_out) / w_out : std::numeric_limits<double>::infinity();
            depth_error[s] = std::max(depth_error[s], e_rel);
          }
      }
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < 4; ++k) {
        const std::size_t s = (std::size_t(j) * n + i) * 4 + k;
        const bool in = grid.covered(i, j);
        if (in && hits[s] == 0) ++err.uncovered_samples;
        if (!in && hits[s] > 0) ++err.spurious_samples;
        if (hits[s] > 1) ++err.overlapping_samples;
        err.max_depth_error_relative = std::max(err.max_depth_error_relative, depth_error[s]);
      }
  return err;
}

}  // namespace cellbake
