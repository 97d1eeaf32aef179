// Error of a simplified face mesh against its dense grid (see simplify_error.h).
#include "stages/simplify/simplify_error.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "stages/cell_buckets.h"
#include "stages/simplify/simplify_grid.h"
#include "stages/simplify/simplify_outline.h"

namespace cellbake {
namespace {

// Offsets chosen so that no segment between lattice points shorter than ~700 px
// passes exactly through a sample.
constexpr double kOffsetX = 0.0313, kOffsetY = 0.0711;

struct ScreenVertex {
  double x, y, w;
};

struct Segment2 {
  double ax, ay, bx, by;
};

double distance_to_segment(double px, double py, const Segment2& s) {
  const double dx = s.bx - s.ax, dy = s.by - s.ay, qx = px - s.ax, qy = py - s.ay;
  const double len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp((qx * dx + qy * dy) / len2, 0.0, 1.0) : 0.0;
  const double ex = qx - t * dx, ey = qy - t * dy;
  return std::sqrt(ex * ex + ey * ey);
}

constexpr double kBoundarySaturationPx = 64;

// Whether (x, y) lies in the closed triangle abc (signed area `orient`), to rounding.
bool contains(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c, double orient, double x, double y) {
  const double tol = 1e-9 * std::abs(orient);
  auto side = [&](const ScreenVertex& p, const ScreenVertex& q) {
    return ((q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x)) * (orient > 0 ? 1 : -1) >= -tol;
  };
  return side(a, b) && side(b, c) && side(c, a);
}

// Segments bucketed on a uniform grid for nearest-distance queries.
class SegmentIndex {
 public:
  SegmentIndex(std::vector<Segment2> segments, int face_size)
      : segments_(std::move(segments)),
        cells_(face_size / kCell + 2),
        buckets_(std::size_t(cells_) * cells_, [&](auto&& visit) { for_each_cell(visit); }) {}

  // Distance d from (px, py) to the nearest segment, at most
  // kBoundarySaturationPx; or, once a scanned cell brings the best distance so
  // far to `enough` or below, that distance (then d <= result <= enough).
  // The nearest point lies in a cell whose bucket holds its segment, and no
  // farther from (px, py) than that cell's square; so a cell no nearer than
  // the best distance so far is skipped (the result is the same as scanning it).
  double distance(double px, double py, double enough = -1) const {
    const int cx = cell(px), cy = cell(py);
    double best = kBoundarySaturationPx;
    auto scan = [&](int x, int y, double gap_y) {
      if (x < 0 || x >= cells_) return false;
      const double gap_x = std::max({0.0, double(x) * kCell - px, px - double(x + 1) * kCell});
      if (gap_x * gap_x + gap_y * gap_y >= best * best) return false;
      for (std::uint32_t k : buckets_[std::size_t(y) * cells_ + x])
        best = std::min(best, distance_to_segment(px, py, segments_[k]));
      return best <= enough;
    };
    for (int ring = 0; ring * kCell <= kBoundarySaturationPx + kCell; ++ring) {
      if ((ring - 1) * kCell >= best) break;
      for (int y = std::max(cy - ring, 0); y <= std::min(cy + ring, cells_ - 1); ++y) {
        const double gap_y = std::max({0.0, double(y) * kCell - py, py - double(y + 1) * kCell});
        if (gap_y >= best) continue;
        if (std::abs(y - cy) == ring) {
          for (int x = cx - ring; x <= cx + ring; ++x)
            if (scan(x, y, gap_y)) return best;
        } else if (scan(cx - ring, y, gap_y) || scan(cx + ring, y, gap_y)) {
          return best;
        }
      }
    }
    return best;
  }

 private:
  static constexpr int kCell = 2;
  int cell(double v) const { return std::clamp(int(std::floor(v / kCell)), 0, cells_ - 1); }
  // Calls visit(segment, cell) for every cell of every segment's bounding box.
  template <typename Visit>
  void for_each_cell(Visit&& visit) const {
    for (std::size_t k = 0; k < segments_.size(); ++k) {
      const Segment2& s = segments_[k];
      const int x0 = cell(std::min(s.ax, s.bx)), x1 = cell(std::max(s.ax, s.bx));
      const int y0 = cell(std::min(s.ay, s.by)), y1 = cell(std::max(s.ay, s.by));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) visit(k, std::size_t(y) * cells_ + x);
    }
  }
  std::vector<Segment2> segments_;
  int cells_;
  CellBuckets buckets_;
};

// Max over points sampled every 1/8 px along `from` of the distance to `to`.
// The distance is 1-Lipschitz along a segment, so a run of samples between two
// measured ones (d0, d1, `gap` px apart) stays below (d0 + d1 + gap) / 2; runs
// whose bound cannot beat the running max are skipped (the result equals
// measuring every sample). A sample no farther than the running max cannot
// raise it, so its query may stop at any distance within the max (an upper
// bound on its own, which keeps the run bounds valid): the result is still
// the max over every sample.
double directed_distance(const std::vector<Segment2>& from, const SegmentIndex& to) {
  struct Sampled {
    const Segment2* s;
    int steps;
    double d0, d1;
  };
  std::vector<Sampled> sampled;
  sampled.reserve(from.size());
  double worst = 0;
  const Segment2* previous = nullptr;  // chains list segments end to start: their shared ends are measured once
  for (const Segment2& s : from) {
    const int steps = std::max(1, int(std::ceil(std::hypot(s.bx - s.ax, s.by - s.ay) * 8)));
    const bool continues = previous && previous->bx == s.ax && previous->by == s.ay;
    const double d0 = continues ? sampled.back().d1 : to.distance(s.ax, s.ay, worst);
    worst = std::max(worst, d0);
    const Sampled m{&s, steps, d0, to.distance(s.bx, s.by, worst)};
    previous = &s;
    worst = std::max(worst, m.d1);
    sampled.push_back(m);
  }
  auto at = [&](const Segment2& s, int k, int steps) {
    const double t = double(k) / steps;
    return to.distance(s.ax + t * (s.bx - s.ax), s.ay + t * (s.by - s.ay), worst);
  };
  struct Run {
    int k0, k1;
    double d0, d1;
  };
  std::vector<Run> stack;
  for (const Sampled& m : sampled) {
    const double step_px = std::hypot(m.s->bx - m.s->ax, m.s->by - m.s->ay) / m.steps;
    stack.push_back({0, m.steps, m.d0, m.d1});
    while (!stack.empty()) {
      const Run r = stack.back();
      stack.pop_back();
      if (r.k1 - r.k0 < 2 || (r.d0 + r.d1 + (r.k1 - r.k0) * step_px) / 2 <= worst) continue;
      const int mid = (r.k0 + r.k1) / 2;
      const double dm = at(*m.s, mid, m.steps);
      worst = std::max(worst, dm);
      stack.push_back({r.k0, mid, r.d0, dm});
      stack.push_back({mid, r.k1, dm, r.d1});
    }
  }
  return worst;
}

// Boundary edges (used by exactly one triangle) of `mesh` in lattice
// coordinates, in the order of their vertex pairs.
std::vector<Segment2> boundary_edges(const FaceMesh& mesh, int n) {
  std::vector<std::uint64_t> edges;  // (lower vertex, higher vertex)
  edges.reserve(mesh.indices.size());
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = mesh.indices[t + e], b = mesh.indices[t + (e + 1) % 3];
      if (a > b) std::swap(a, b);
      edges.push_back((std::uint64_t(a) << 32) | b);
    }
  std::sort(edges.begin(), edges.end());
  std::vector<Segment2> out;
  for (std::size_t k = 0; k < edges.size();) {
    std::size_t m = k;
    while (m < edges.size() && edges[m] == edges[k]) ++m;
    if (m - k == 1) {
      const Uv a = mesh.uvs[edges[k] >> 32], b = mesh.uvs[edges[k] & 0xffffffffu];
      out.push_back({double(a.u) * n, double(a.v) * n, double(b.u) * n, double(b.v) * n});
    }
    k = m;
  }
  return out;
}

// Where a unit lattice edge is recorded in a mask over the (n + 1)^2 lattice
// points of an n-pixel face: at its lower-left end, bit 1 when it runs along
// x, bit 2 along y; false when s is not such an edge (ends not integral, not
// one pixel apart along an axis, or off the face).
bool unit_edge_slot(const Segment2& s, int n, std::size_t& at, std::uint8_t& bit) {
  const double x0 = std::min(s.ax, s.bx), y0 = std::min(s.ay, s.by);
  const double dx = std::abs(s.bx - s.ax), dy = std::abs(s.by - s.ay);
  if (!(x0 >= 0 && y0 >= 0 && x0 <= n && y0 <= n) || x0 != std::floor(x0) || y0 != std::floor(y0)) return false;
  if (dx == 1 && dy == 0 && x0 + 1 <= n) {
    bit = 1;
  } else if (dx == 0 && dy == 1 && y0 + 1 <= n) {
    bit = 2;
  } else {
    return false;
  }
  at = std::size_t(y0) * std::size_t(n + 1) + std::size_t(x0);
  return true;
}

// `from` without the unit lattice edges that `other` holds too. Every point
// sampled on such an edge is exactly 0 px from the same edge in `other` (its
// coordinates are exact multiples of 1/8), so dropping these edges never
// changes directed_distance(from, index of a superset of other).
std::vector<Segment2> without_shared_unit_edges(const std::vector<Segment2>& from, const std::vector<Segment2>& other,
                                                int n) {
  std::vector<std::uint8_t> mask(std::size_t(n + 1) * std::size_t(n + 1), 0);
  std::size_t at = 0;
  std::uint8_t bit = 0;
  for (const Segment2& s : other)
    if (unit_edge_slot(s, n, at, bit)) mask[at] |= bit;
  std::vector<Segment2> out;
  out.reserve(from.size());
  for (const Segment2& s : from)
    if (!unit_edge_slot(s, n, at, bit) || !(mask[at] & bit)) out.push_back(s);
  return out;
}

// Whether segment s lies on a side of the n-pixel face square.
bool on_face_side(const Segment2& s, int n) {
  auto same_side = [&](double p, double q) {
    return (std::abs(p) < 1e-4 && std::abs(q) < 1e-4) || (std::abs(p - n) < 1e-4 && std::abs(q - n) < 1e-4);
  };
  return same_side(s.ax, s.bx) || same_side(s.ay, s.by);
}

// Per simplified vertex: the region of the dense vertex it copies (same
// lattice point, bit-identical position), or -1 when it copies none or that
// vertex is shared by pixels of several regions.
std::vector<std::int32_t> simplified_vertex_regions(const FaceMesh& dense, const FaceGrid& grid,
                                                    const FaceRegions& regions, const FaceMesh& simplified) {
  const int n = grid.size;
  std::vector<std::int32_t> dense_region(dense.positions.size(), -2);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (!grid.covered(i, j)) continue;
      const std::int32_t l = regions.label[std::size_t(j) * n + i];
      for (std::uint32_t v : grid.corner_vertex[std::size_t(j) * n + i])
        dense_region[v] = dense_region[v] == -2 || dense_region[v] == l ? l : -1;
    }
  std::vector<std::int32_t> out(simplified.positions.size(), -1);
  for (std::size_t v = 0; v < out.size(); ++v) {
    const int x = int(std::lround(double(simplified.uvs[v].u) * n)), y = int(std::lround(double(simplified.uvs[v].v) * n));
    const Vec3f p = simplified.positions[v];
    for (int j = y - 1; j <= y && out[v] < 0; ++j)
      for (int i = x - 1; i <= x && out[v] < 0; ++i) {
        if (i < 0 || j < 0 || i >= n || j >= n || !grid.covered(i, j)) continue;
        const std::uint32_t d = grid.vertex(i, j, x, y);
        const Vec3f q = dense.positions[d];
        if (q.x == p.x && q.y == p.y && q.z == p.z && dense_region[d] >= 0) out[v] = dense_region[d];
      }
  }
  return out;
}

}  // namespace

SimplifyError measure_simplification_error(const FaceMesh& dense, const FaceMesh& simplified, int face_size) {
  const FaceGrid grid = read_face_grid(dense, face_size);
  const FaceRegions regions = label_face_regions(grid);
  return measure_simplification_error(dense, grid, regions, trace_face_outlines(grid, regions), simplified);
}

SimplifyError measure_simplification_error(const FaceMesh& dense, const FaceGrid& grid, const FaceRegions& regions,
                                           const FaceOutlines& outlines, const FaceMesh& simplified) {
  const int n = grid.size;
  std::vector<ScreenVertex> sv(simplified.positions.size());
  for (std::size_t v = 0; v < sv.size(); ++v) {
    const double x = double(simplified.uvs[v].u) * n, y = double(simplified.uvs[v].v) * n;
    sv[v] = {x, y, inverse_planar_depth(simplified.positions[v], x, y, n)};
  }
  const std::vector<std::int32_t> vertex_region = simplified_vertex_regions(dense, grid, regions, simplified);
  SimplifyError err;
  // Per sample: how many simplified triangles cover it.
  std::vector<std::uint8_t> hits(std::size_t(n) * n * 4, 0);
  const std::size_t nt = simplified.indices.size() / 3;
  for (std::size_t t = 0; t < nt; ++t) {
    const ScreenVertex& a = sv[simplified.indices[3 * t]];
    const ScreenVertex& b = sv[simplified.indices[3 * t + 1]];
    const ScreenVertex& c = sv[simplified.indices[3 * t + 2]];
    const double orient = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (orient == 0 || (orient > 0 ? 1 : -1) != grid.orientation) ++err.flipped_triangles;
    // The surface region the triangle stands for: the one region of its
    // vertices that belong to a single region (-1: none, or they disagree).
    std::int32_t region = -1;
    for (int k = 0; k < 3; ++k) {
      const std::int32_t r = vertex_region[simplified.indices[3 * t + k]];
      if (r < 0) continue;
      if (region >= 0 && r != region) {
        region = -1;
        break;
      }
      region = r;
    }
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
            if (outlines.on_outline[std::size_t(j + dy) * (n + 1) + i + dx]) continue;
            // Another surface moved over this pixel by a displaced outline:
            // a coverage change (measured above), not a depth error.
            if (region >= 0 && regions.label[std::size_t(j) * n + i] != region) continue;
            // The surface on the vertex's own eye ray: only a triangle holding the vertex.
            if (!contains(a, b, c, orient, i + dx, j + dy)) continue;
            const std::uint32_t v = grid.vertex(i, j, i + dx, j + dy);
            const double w_out = alpha * grid.x[v] + beta * grid.y[v] + gamma;
            if (!(w_out > 0)) {
              err.max_depth_error_relative = std::numeric_limits<double>::infinity();
              continue;
            }
            // Divides only where the quotient may exceed the max so far (a
            // correctly rounded quotient above it needs |dw| >= max * w_out,
            // so the margin keeps every such case): the same max.
            const double dw = std::abs(grid.w[v] - w_out);
            if (dw > err.max_depth_error_relative * w_out * (1 - 1e-9))
              err.max_depth_error_relative = std::max(err.max_depth_error_relative, dw / w_out);
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
      }
  // Outlines: the simplified boundary off the face sides is compared with all
  // of the dense boundary (its ends may meet the face sides) and vice versa.
  // The dense outline edges are the traced chains' unit edges (the same as
  // its boundary edges off the face sides, without sorting a million edges).
  std::vector<Segment2> dense_outline;
  for (const OutlineChain& c : outlines.chains)
    for (std::size_t k = 0; k + 1 < c.points.size(); ++k)
      dense_outline.push_back({double(c.points[k].x), double(c.points[k].y), double(c.points[k + 1].x),
                               double(c.points[k + 1].y)});
  std::vector<Segment2> simplified_boundary = boundary_edges(simplified, n);
  std::vector<Segment2> simplified_outline;
  for (const Segment2& s : simplified_boundary)
    if (!on_face_side(s, n)) simplified_outline.push_back(s);
  if (!dense_outline.empty() || !simplified_outline.empty()) {
    std::vector<Segment2> dense_boundary = dense_outline;  // plus the covered face-side edges
    for (int t = 0; t < n; ++t) {
      if (grid.covered(t, 0)) dense_boundary.push_back({double(t), 0, double(t + 1), 0});
      if (grid.covered(t, n - 1)) dense_boundary.push_back({double(t), double(n), double(t + 1), double(n)});
      if (grid.covered(0, t)) dense_boundary.push_back({0, double(t), 0, double(t + 1)});
      if (grid.covered(n - 1, t)) dense_boundary.push_back({double(n), double(t), double(n), double(t + 1)});
    }
    // Edges both outlines share are 0 px from the other one: only the rest is measured.
    const std::vector<Segment2> simplified_moved = without_shared_unit_edges(simplified_outline, dense_outline, n);
    const std::vector<Segment2> dense_moved = without_shared_unit_edges(dense_outline, simplified_boundary, n);
    const SegmentIndex dense_index(std::move(dense_boundary), n);
    const SegmentIndex simplified_index(std::move(simplified_boundary), n);
    err.max_boundary_error_px =
        std::max(directed_distance(simplified_moved, dense_index), directed_distance(dense_moved, simplified_index));
  }
  return err;
}

}  // namespace cellbake
