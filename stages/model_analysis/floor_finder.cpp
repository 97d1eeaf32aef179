#include "stages/model_analysis/floor_finder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cellbake {
namespace {

struct Hit {
  double height = 0;
  double up_cos = 0;  // unit normal · up of the surface hit (signed: its winding)
};

struct RayGrid {
  int a = 0, b = 0;           // horizontal axes
  double lo_a = 0, lo_b = 0;  // grid origin
  double step_a = 0, step_b = 0;
  int na = 0, nb = 0;
  double a_of(int i) const { return lo_a + (i + 0.5) * step_a; }
  double b_of(int j) const { return lo_b + (j + 0.5) * step_b; }
};

RayGrid make_grid(const Box3d& bounds, const FloorFinderParams& p) {
  RayGrid g;
  g.a = 0;
  g.b = p.up_axis == 2 ? 1 : 2;
  const double ext_a = bounds.hi[g.a] - bounds.lo[g.a], ext_b = bounds.hi[g.b] - bounds.lo[g.b];
  const double longer = std::max(ext_a, ext_b);
  if (!(longer > 0)) return g;  // a point or a vertical line: no grid
  const double step = longer / std::max(2, p.grid);
  g.na = std::max(2, int(std::ceil(ext_a / step)));
  g.nb = std::max(2, int(std::ceil(ext_b / step)));
  g.lo_a = bounds.lo[g.a];
  g.lo_b = bounds.lo[g.b];
  g.step_a = ext_a > 0 ? ext_a / g.na : step;
  g.step_b = ext_b > 0 ? ext_b / g.nb : step;
  if (!(ext_a > 0)) g.lo_a -= 0.5 * g.na * g.step_a;
  if (!(ext_b > 0)) g.lo_b -= 0.5 * g.nb * g.step_b;
  return g;
}

// Every grid ray the triangle's horizontal projection covers gets a hit at the
// triangle's height there. Vertical triangles (walls) are skipped: a vertical
// ray only grazes them.
void rasterise(const RayGrid& g, int up, Vec3d p0, Vec3d p1, Vec3d p2, std::vector<std::vector<Hit>>& hits) {
  const Vec3d n = cross(p1 - p0, p2 - p0);
  const double len = length(n);
  if (!(len > 0)) return;
  const double up_cos = n[up] / len;
  if (std::abs(up_cos) < 1e-3) return;
  const double a0 = p0[g.a], a1 = p1[g.a], a2 = p2[g.a];
  const double b0 = p0[g.b], b1 = p1[g.b], b2 = p2[g.b];
  const double area = (a1 - a0) * (b2 - b0) - (a2 - a0) * (b1 - b0);
  if (area == 0) return;
  const int i0 = std::max(0, int(std::ceil((std::min({a0, a1, a2}) - g.lo_a) / g.step_a - 0.5)));
  const int i1 = std::min(g.na - 1, int(std::floor((std::max({a0, a1, a2}) - g.lo_a) / g.step_a - 0.5)));
  const int j0 = std::max(0, int(std::ceil((std::min({b0, b1, b2}) - g.lo_b) / g.step_b - 0.5)));
  const int j1 = std::min(g.nb - 1, int(std::floor((std::max({b0, b1, b2}) - g.lo_b) / g.step_b - 0.5)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double pa = g.a_of(i), pb = g.b_of(j);
      // Barycentric weights from signed sub-areas; inclusive on the edges.
      const double w0 = ((a1 - pa) * (b2 - pb) - (a2 - pa) * (b1 - pb)) / area;
      const double w1 = ((a2 - pa) * (b0 - pb) - (a0 - pa) * (b2 - pb)) / area;
      const double w2 = 1.0 - w0 - w1;
      constexpr double kEdge = -1e-9;
      if (w0 < kEdge || w1 < kEdge || w2 < kEdge) continue;
      hits[std::size_t(j) * g.na + i].push_back({w0 * p0[up] + w1 * p1[up] + w2 * p2[up], up_cos});
    }
}

// The walkable hits of one ray (sorted by height): facing up (per `sign`, the
// winding taken as up) with `min_headroom` free above. `covered`: something above.
struct Walkable {
  double height;
  bool covered;
};
std::vector<Walkable> walkable_hits(const std::vector<Hit>& ray, double sign, const FloorFinderParams& p) {
  std::vector<Walkable> out;
  const double same = 0.5 * p.bin_size;  // coincident surfaces (a slab's duplicates) are not a ceiling
  for (std::size_t k = 0; k < ray.size(); ++k) {
    if (sign * ray[k].up_cos < p.min_up_cos) continue;
    const double h = ray[k].height;
    std::size_t above = k + 1;
    while (above < ray.size() && ray[above].height <= h + same) ++above;
    if (above < ray.size() && ray[above].height - h < p.min_headroom) continue;
    if (!out.empty() && h - out.back().height <= same) continue;  // one hit per floor per ray
    out.push_back({h, above < ray.size()});
  }
  return out;
}

std::vector<Floor> floors_of(const std::vector<std::vector<Hit>>& hits, const RayGrid& g, double lo_up,
                             double sign, std::uint64_t rays_hit, const FloorFinderParams& p) {
  std::vector<std::vector<Walkable>> walk(hits.size());
  double top = lo_up;
  for (std::size_t r = 0; r < hits.size(); ++r) {
    walk[r] = walkable_hits(hits[r], sign, p);
    for (const Walkable& w : walk[r]) top = std::max(top, w.height);
  }
  const std::size_t bins = std::size_t((top - lo_up) / p.bin_size) + 1;
  std::vector<std::uint64_t> count(bins, 0), covered(bins, 0);
  std::vector<double> sum(bins, 0);
  for (const auto& ray : walk) {
    std::size_t last = bins;  // one count per ray per bin
    for (const Walkable& w : ray) {
      const std::size_t bin = std::min(bins - 1, std::size_t((w.height - lo_up) / p.bin_size));
      sum[bin] += w.height;
      if (bin != last) ++count[bin], covered[bin] += w.covered ? 1 : 0;
      last = bin;
    }
  }
  // Peaks, indoor ones first (most rays with something above: a floor under a
  // roof wins over the ground around the building a little below it), then
  // the strongest; one within min_separation of a chosen one is the same floor.
  std::vector<std::size_t> order(bins);
  for (std::size_t i = 0; i < bins; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return covered[x] != covered[y] ? covered[x] > covered[y] : count[x] > count[y];
  });
  const double need = std::max(1.0, p.min_fraction * double(rays_hit));
  std::vector<double> heights;
  for (std::size_t bin : order) {
    if (double(count[bin]) < need) continue;
    bool near = false;
    const double h = sum[bin] / double(count[bin] ? count[bin] : 1);
    for (double chosen : heights) near = near || std::abs(chosen - h) < p.min_separation;
    if (!near) heights.push_back(h);
  }
  std::sort(heights.begin(), heights.end());
  std::vector<Floor> floors(heights.size());
  for (std::size_t f = 0; f < heights.size(); ++f) floors[f].height = heights[f];
  for (std::size_t r = 0; r < walk.size(); ++r) {
    const int i = int(r % std::size_t(g.na)), j = int(r / std::size_t(g.na));
    for (Floor& f : floors) {
      for (const Walkable& w : walk[r]) {
        if (std::abs(w.height - f.height) > 0.5 * p.min_separation) continue;
        ++f.rays;
        Vec3d pt;
        pt[g.a] = g.a_of(i);
        pt[g.b] = g.b_of(j);
        pt[p.up_axis] = w.height;
        f.extent.expand(pt);
        if (w.covered) ++f.covered_rays, f.covered_extent.expand(pt);
        break;
      }
    }
  }
  return floors;
}

}  // namespace

FloorFinderResult find_floors(const ChunkSource& source, const FloorFinderParams& p) {
  if (p.up_axis != 1 && p.up_axis != 2)
    throw std::invalid_argument("find_floors: up_axis must be 1 (y) or 2 (z)");
  if (!(p.bin_size > 0) || p.grid < 2)
    throw std::invalid_argument("find_floors: bin_size must be > 0 and grid >= 2");
  FloorFinderResult result;
  const Box3d bounds = source.model_bounds();
  if (bounds.empty()) return result;
  const RayGrid g = make_grid(bounds, p);
  if (g.na == 0) return result;
  result.rays = std::uint64_t(g.na) * std::uint64_t(g.nb);
  result.ray_spacing = std::max(g.step_a, g.step_b);
  std::vector<std::vector<Hit>> hits(result.rays);
  for (const ChunkRef& ref : source.query(bounds)) {
    const auto chunk = source.load(ref.id);
    for (std::size_t t = 0; t + 2 < chunk->indices.size(); t += 3)
      rasterise(g, p.up_axis, chunk->world(chunk->indices[t]), chunk->world(chunk->indices[t + 1]),
                chunk->world(chunk->indices[t + 2]), hits);
  }
  for (auto& ray : hits) {
    std::sort(ray.begin(), ray.end(), [](const Hit& x, const Hit& y) { return x.height < y.height; });
    if (!ray.empty()) ++result.rays_hit;
  }
  result.floors = floors_of(hits, g, bounds.lo[p.up_axis], 1.0, result.rays_hit, p);
  // A model whose floors are wound facing down (no upward floors at all): take the other winding.
  if (result.floors.empty())
    result.floors = floors_of(hits, g, bounds.lo[p.up_axis], -1.0, result.rays_hit, p);
  return result;
}

}  // namespace cellbake
