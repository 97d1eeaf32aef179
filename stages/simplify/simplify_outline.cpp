// Region outlines and their straightening (see simplify_outline.h).
// Douglas & Peucker 1973, "Algorithms for the reduction of the number of
// points required to represent a digitized line or its caricature"; the
// crossing repair follows the usual topology-preserving variant (re-insert the
// farthest dropped point of an offending segment until no segments intersect).
#include "stages/simplify/simplify_outline.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include "stages/cell_buckets.h"

namespace cellbake {
namespace {

// --- regions -----------------------------------------------------------------

int find_root(std::vector<std::int32_t>& parent, int x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

// Pixels p (left/top) and q (right/bottom) share the vertices of their common
// side; `horizontal` = q is the east neighbour.
bool share_side(const FaceGrid& g, int pi, int pj, int qi, int qj) {
  if (!g.covered(pi, pj) || !g.covered(qi, qj)) return false;
  if (qi > pi) {  // east: common side x = qi, y in [pj, pj + 1]
    return g.vertex(pi, pj, qi, pj) == g.vertex(qi, qj, qi, qj) && g.vertex(pi, pj, qi, pj + 1) == g.vertex(qi, qj, qi, qj + 1);
  }
  // south: common side y = qj, x in [pi, pi + 1]
  return g.vertex(pi, pj, pi, qj) == g.vertex(qi, qj, qi, qj) && g.vertex(pi, pj, pi + 1, qj) == g.vertex(qi, qj, qi + 1, qj);
}

// --- outline edges -----------------------------------------------------------

class OutlineEdges {
 public:
  OutlineEdges(const FaceGrid& g, const FaceRegions& r) : n_(g.size) {
    // Horizontal edge (x, y)-(x+1, y), 0 < y < n: pixels (x, y-1) and (x, y).
    // Vertical edge (x, y)-(x, y+1), 0 < x < n: pixels (x-1, y) and (x, y).
    horizontal_.assign(std::size_t(n_ + 1) * (n_ + 1), 0);
    vertical_.assign(std::size_t(n_ + 1) * (n_ + 1), 0);
    auto label = [&](int i, int j) { return r.label[std::size_t(j) * n_ + i]; };
    if (r.joins.size() != std::size_t(n_) * n_ || r.label.size() != r.joins.size())
      throw std::invalid_argument("simplify: face regions do not match a " + std::to_string(n_) + "^2 face");
    auto joins = [&](int i, int j, std::uint8_t side) { return (r.joins[std::size_t(j) * n_ + i] & side) != 0; };
    for (int y = 1; y < n_; ++y)
      for (int x = 0; x < n_; ++x) {
        const int a = label(x, y - 1), b = label(x, y);
        horizontal_[index(x, y)] = (a != b) || (a >= 0 && !joins(x, y - 1, FaceRegions::kJoinsSouth));
      }
    for (int y = 0; y < n_; ++y)
      for (int x = 1; x < n_; ++x) {
        const int a = label(x - 1, y), b = label(x, y);
        vertical_[index(x, y)] = (a != b) || (a >= 0 && !joins(x - 1, y, FaceRegions::kJoinsEast));
      }
  }

  std::size_t index(int x, int y) const { return std::size_t(y) * (n_ + 1) + x; }
  bool horizontal(int x, int y) const { return x >= 0 && y >= 0 && x < n_ && y <= n_ && horizontal_[index(x, y)]; }
  bool vertical(int x, int y) const { return x >= 0 && y >= 0 && x <= n_ && y < n_ && vertical_[index(x, y)]; }

  // Outline edges at point p, as unit steps (E, S, W, N order).
  int steps(LatticePoint p, std::array<LatticePoint, 4>& out) const {
    int k = 0;
    if (horizontal(p.x, p.y)) out[k++] = {1, 0};
    if (vertical(p.x, p.y)) out[k++] = {0, 1};
    if (horizontal(p.x - 1, p.y)) out[k++] = {-1, 0};
    if (vertical(p.x, p.y - 1)) out[k++] = {0, -1};
    return k;
  }

  bool edge(LatticePoint p, LatticePoint step) const {
    if (step.x == 1) return horizontal(p.x, p.y);
    if (step.x == -1) return horizontal(p.x - 1, p.y);
    if (step.y == 1) return vertical(p.x, p.y);
    return vertical(p.x, p.y - 1);
  }
  // Visited flag of the edge leaving p by `step`.
  std::uint8_t& visited(LatticePoint p, LatticePoint step) {
    if (step.x == 1) return visited_h(p.x, p.y);
    if (step.x == -1) return visited_h(p.x - 1, p.y);
    if (step.y == 1) return visited_v(p.x, p.y);
    return visited_v(p.x, p.y - 1);
  }

  int size() const { return n_; }

 private:
  std::uint8_t& visited_h(int x, int y) { return horizontal_[index(x, y)]; }  // 1 = unvisited edge, 2 = visited
  std::uint8_t& visited_v(int x, int y) { return vertical_[index(x, y)]; }

  int n_;
  std::vector<std::uint8_t> horizontal_, vertical_;
};

// --- geometry ----------------------------------------------------------------

double distance_to_segment(LatticePoint p, LatticePoint a, LatticePoint b) {
  const double dx = b.x - a.x, dy = b.y - a.y, px = p.x - a.x, py = p.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? (px * dx + py * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const double ex = px - t * dx, ey = py - t * dy;
  return std::sqrt(ex * ex + ey * ey);
}

long orient(LatticePoint a, LatticePoint b, LatticePoint c) {
  return long(b.x - a.x) * (c.y - a.y) - long(b.y - a.y) * (c.x - a.x);
}

bool on_segment(LatticePoint p, LatticePoint a, LatticePoint b) {
  return orient(a, b, p) == 0 && std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

// Whether segments (a, b) and (c, d) meet anywhere other than at one shared end
// point where they leave in different directions.
bool segments_conflict(LatticePoint a, LatticePoint b, LatticePoint c, LatticePoint d) {
  const int shared = (a == c) + (a == d) + (b == c) + (b == d);
  if (shared >= 2) return true;
  if (shared == 1) {
    const LatticePoint p = (a == c || a == d) ? a : b;
    const LatticePoint u = p == a ? b : a, v = p == c ? d : c;
    return orient(p, u, v) == 0 && long(u.x - p.x) * (v.x - p.x) + long(u.y - p.y) * (v.y - p.y) > 0;
  }
  const long o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return true;
  return on_segment(c, a, b) || on_segment(d, a, b) || on_segment(a, c, d) || on_segment(b, c, d);
}

// Relative depth error of side w-values at point k against the segment [i, j]
// (interpolated at the parameter of k's nearest point on it).
double side_depth_error(const OutlineChain& c, std::size_t i, std::size_t j, std::size_t k) {
  const LatticePoint a = c.points[i], b = c.points[j], p = c.points[k];
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
  double worst = 0;
  for (const std::vector<double>* w : {&c.w_left, &c.w_right}) {
    const double wa = (*w)[i], wb = (*w)[j], wk = (*w)[k];
    if (!(wa > 0 && wb > 0 && wk > 0)) continue;
    const double wi = (1 - t) * wa + t * wb;
    worst = std::max(worst, std::abs(wk - wi) / wi);
  }
  return worst;
}

void douglas_peucker(OutlineChain& c, std::size_t first, std::size_t last, double tolerance, double depth_error) {
  std::vector<std::pair<std::size_t, std::size_t>> stack{{first, last}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j <= i + 1) continue;
    double worst = -1, worst_depth = -1;
    std::size_t at = i, at_depth = i;
    for (std::size_t k = i + 1; k < j; ++k) {
      const double d = distance_to_segment(c.points[k], c.points[i], c.points[j]);
      if (d > worst) worst = d, at = k;
      const double e = side_depth_error(c, i, j, k);
      if (e > worst_depth) worst_depth = e, at_depth = k;
    }
    if (worst <= tolerance) {
      if (worst_depth <= depth_error) continue;
      at = at_depth;
    }
    c.kept[at] = 1;
    stack.push_back({at, j});
    stack.push_back({i, at});
  }
}

// Keeps the inner point of chain segment [i, j] farthest from the segment
// (ties: the first), then straightens both halves again within the bounds.
// Returns false when there is none.
bool keep_farthest(OutlineChain& c, std::size_t i, std::size_t j, double tolerance, double depth_error) {
  if (j <= i + 1) return false;
  double worst = -1;
  std::size_t at = i + 1;
  for (std::size_t k = i + 1; k < j; ++k) {
    const double d = distance_to_segment(c.points[k], c.points[i], c.points[j]);
    if (d > worst) worst = d, at = k;
  }
  c.kept[at] = 1;
  douglas_peucker(c, i, at, tolerance, depth_error);
  douglas_peucker(c, at, j, tolerance, depth_error);
  return true;
}

struct Segment {
  LatticePoint a, b;
  int chain;  // -1: fixed
  std::size_t i, j;
};

// Repairs crossings until none is left; every pass re-inserts one point into
// each chain segment that conflicts with another segment or joins the two
// sides of its outline at both ends.
// Segments that meet share a lattice point, so they share the grid cell that
// holds it: pairs are tested within cells only, after a bounding-box test.
void repair_crossings(FaceOutlines& outlines, const std::vector<FixedSegment>& fixed, int face_size) {
  constexpr int kCell = 4;
  const int cells = face_size / kCell + 1;
  for (;;) {
    std::vector<Segment> segments;
    for (const FixedSegment& f : fixed) segments.push_back({f.a, f.b, -1, 0, 0});
    for (std::size_t c = 0; c < outlines.chains.size(); ++c) {
      const OutlineChain& ch = outlines.chains[c];
      std::size_t prev = 0;
      for (std::size_t k = 1; k < ch.points.size(); ++k)
        if (ch.kept[k]) {
          segments.push_back({ch.points[prev], ch.points[k], int(c), prev, k});
          prev = k;
        }
    }
    const CellBuckets buckets(std::size_t(cells) * cells, [&](auto&& visit) {
      for (std::size_t s = 0; s < segments.size(); ++s) {
        const Segment& g = segments[s];
        const int x0 = std::min(g.a.x, g.b.x) / kCell, x1 = std::max(g.a.x, g.b.x) / kCell;
        const int y0 = std::min(g.a.y, g.b.y) / kCell, y1 = std::max(g.a.y, g.b.y) / kCell;
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) visit(s, std::size_t(y) * cells + x);
      }
    });
    std::vector<std::uint8_t> conflict(segments.size(), 0);
    for (std::size_t s = 0; s < segments.size(); ++s) {
      const Segment& g = segments[s];
      if (g.chain >= 0 && g.j > g.i + 1 && outlines.chains[g.chain].joined[g.i] && outlines.chains[g.chain].joined[g.j])
        conflict[s] = 1;
    }
    for (std::size_t c = 0; c < buckets.cell_count(); ++c) {
      const std::span<const std::uint32_t> members = buckets[c];
      for (std::size_t p = 0; p < members.size(); ++p)
        for (std::size_t q = p + 1; q < members.size(); ++q) {
          const Segment& s = segments[members[p]];
          const Segment& t = segments[members[q]];
          if (s.chain < 0 && t.chain < 0) continue;
          if (std::max(s.a.x, s.b.x) < std::min(t.a.x, t.b.x) || std::max(t.a.x, t.b.x) < std::min(s.a.x, s.b.x) ||
              std::max(s.a.y, s.b.y) < std::min(t.a.y, t.b.y) || std::max(t.a.y, t.b.y) < std::min(s.a.y, s.b.y))
            continue;  // apart: no shared point
          if (segments_conflict(s.a, s.b, t.a, t.b)) conflict[members[p]] = conflict[members[q]] = 1;
        }
    }
    bool changed = false;
    for (std::size_t s = 0; s < segments.size(); ++s)
      if (conflict[s] && segments[s].chain >= 0)
        changed |= keep_farthest(outlines.chains[segments[s].chain], segments[s].i, segments[s].j,
                                 outlines.tolerance_px, outlines.depth_error_relative);
    if (!changed) return;  // remaining conflicts are between unit staircase edges: none exist
  }
}

// Vertices of the two pixels beside unit edge a -> b at lattice point p (an end of it).
bool sides_share_vertex(const FaceGrid& g, LatticePoint a, LatticePoint b, LatticePoint p) {
  const int n = g.size;
  int li, lj, ri, rj;  // pixels left and right of the edge
  if (b.x != a.x) {    // horizontal: pixels above and below
    const int x = std::min(a.x, b.x);
    li = x, lj = a.y - 1, ri = x, rj = a.y;
  } else {
    const int y = std::min(a.y, b.y);
    li = a.x - 1, lj = y, ri = a.x, rj = y;
  }
  auto in = [&](int i, int j) { return i >= 0 && j >= 0 && i < n && j < n && g.covered(i, j); };
  if (!in(li, lj) || !in(ri, rj)) return false;
  return g.vertex(li, lj, p.x, p.y) == g.vertex(ri, rj, p.x, p.y);
}

void mark_joined(const FaceGrid& g, OutlineChain& c) {
  const std::size_t m = c.points.size();
  c.joined.assign(m, 0);
  c.w_left.assign(m, 0);
  c.w_right.assign(m, 0);
  const int n = g.size;
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t e = k + 1 < m ? k : k - 1;  // an edge touching point k
    const LatticePoint a = c.points[e], b = c.points[e + 1], p = c.points[k];
    c.joined[k] = sides_share_vertex(g, a, b, p);
    // Pixels left and right of the walking direction a -> b (x right, y down).
    int li, lj, ri, rj;
    if (b.x > a.x) li = a.x, lj = a.y - 1, ri = a.x, rj = a.y;
    else if (b.x < a.x) li = b.x, lj = a.y, ri = b.x, rj = a.y - 1;
    else if (b.y > a.y) li = a.x, lj = a.y, ri = a.x - 1, rj = a.y;
    else li = a.x - 1, lj = b.y, ri = a.x, rj = b.y;
    auto w = [&](int i, int j) {
      return i >= 0 && j >= 0 && i < n && j < n && g.covered(i, j) ? g.w[g.vertex(i, j, p.x, p.y)] : 0.0;
    };
    c.w_left[k] = w(li, lj);
    c.w_right[k] = w(ri, rj);
  }
}

}  // namespace

FaceRegions label_face_regions(const FaceGrid& g) {
  const int n = g.size;
  const std::size_t count = std::size_t(n) * n;
  std::vector<std::int32_t> parent(count);
  std::iota(parent.begin(), parent.end(), 0);
  auto join = [&](std::size_t a, std::size_t b) {
    const int ra = find_root(parent, int(a)), rb = find_root(parent, int(b));
    parent[std::max(ra, rb)] = std::min(ra, rb);
  };
  FaceRegions r;
  r.joins.assign(count, 0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::size_t p = std::size_t(j) * n + i;
      if (i + 1 < n && share_side(g, i, j, i + 1, j)) join(p, p + 1), r.joins[p] |= FaceRegions::kJoinsEast;
      if (j + 1 < n && share_side(g, i, j, i, j + 1)) join(p, p + n), r.joins[p] |= FaceRegions::kJoinsSouth;
    }
  r.label.assign(count, -1);
  std::vector<std::int32_t> root_label(count, -1);
  for (std::size_t p = 0; p < count; ++p) {
    if (!g.covered(int(p % n), int(p / n))) continue;
    const int root = find_root(parent, int(p));
    if (root_label[root] < 0) root_label[root] = r.count++;
    r.label[p] = root_label[root];
  }
  return r;
}

FaceOutlines trace_face_outlines(const FaceGrid& g, const FaceRegions& regions) {
  const int n = g.size;
  OutlineEdges edges(g, regions);
  FaceOutlines out;
  out.on_outline.assign(std::size_t(n + 1) * (n + 1), 0);
  std::vector<std::uint8_t> degree(std::size_t(n + 1) * (n + 1), 0);
  std::array<LatticePoint, 4> steps{};
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      const int k = edges.steps({x, y}, steps);
      degree[edges.index(x, y)] = std::uint8_t(k);
      out.on_outline[edges.index(x, y)] = k > 0;
    }
  auto is_node = [&](LatticePoint p) {
    return degree[edges.index(p.x, p.y)] != 2 || p.x == 0 || p.y == 0 || p.x == n || p.y == n;
  };
  // Walks from p along `step` until a node (or back at `stop`); marks edges visited.
  auto walk = [&](LatticePoint p, LatticePoint step, LatticePoint stop, bool stop_anywhere_at_nodes) {
    OutlineChain c;
    c.points.push_back(p);
    for (;;) {
      edges.visited(p, step) = 2;
      const LatticePoint q{p.x + step.x, p.y + step.y};
      c.points.push_back(q);
      if ((stop_anywhere_at_nodes && is_node(q)) || q == stop) break;
      const int k = edges.steps(q, steps);
      LatticePoint next{0, 0};
      bool found = false;
      for (int s = 0; s < k; ++s)
        if (!(steps[s].x == -step.x && steps[s].y == -step.y) && edges.visited(q, steps[s]) == 1) {
          next = steps[s];
          found = true;
          break;
        }
      if (!found) break;
      p = q;
      step = next;
    }
    c.kept.assign(c.points.size(), 0);
    if (!c.kept.empty()) c.kept.front() = c.kept.back() = 1;  // a chain has at least its start point
    return c;
  };
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      const LatticePoint p{x, y};
      if (degree[edges.index(x, y)] == 0 || !is_node(p)) continue;
      const int k = edges.steps(p, steps);
      const std::array<LatticePoint, 4> from = steps;
      for (int s = 0; s < k; ++s)
        if (edges.visited(p, from[s]) == 1) out.chains.push_back(walk(p, from[s], p, true));
    }
  // Closed loops without nodes: start at their first point in row-major order.
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      const LatticePoint p{x, y};
      const int k = edges.steps(p, steps);
      const std::array<LatticePoint, 4> from = steps;
      for (int s = 0; s < k; ++s) {
        if (edges.visited(p, from[s]) != 1) continue;
        OutlineChain loop = walk(p, from[s], p, false);
        // Cut at the point farthest from p (first in walking order).
        std::size_t far = 1;
        long best = -1;
        for (std::size_t q = 1; q + 1 < loop.points.size(); ++q) {
          const long dx = loop.points[q].x - p.x, dy = loop.points[q].y - p.y;
          if (dx * dx + dy * dy > best) best = dx * dx + dy * dy, far = q;
        }
        OutlineChain first, second;
        first.points.assign(loop.points.begin(), loop.points.begin() + far + 1);
        second.points.assign(loop.points.begin() + far, loop.points.end());
        for (OutlineChain* c : {&first, &second}) {
          c->kept.assign(c->points.size(), 0);
          c->kept.front() = c->kept.back() = 1;
          out.chains.push_back(std::move(*c));
        }
      }
    }
  for (OutlineChain& c : out.chains) mark_joined(g, c);
  return out;
}

void straighten_face_outlines(FaceOutlines& outlines, const std::vector<FixedSegment>& fixed, double tolerance_px,
                              double depth_error_relative, int face_size) {
  outlines.tolerance_px = tolerance_px;
  outlines.depth_error_relative = depth_error_relative;
  for (OutlineChain& c : outlines.chains)
    douglas_peucker(c, 0, c.points.size() - 1, tolerance_px, depth_error_relative);
  repair_crossings(outlines, fixed, face_size);
}

bool refine_outline_segments(FaceOutlines& outlines, const std::vector<ChainSegment>& segments,
                             const std::vector<FixedSegment>& fixed, int face_size) {
  bool changed = false;
  for (const ChainSegment& s : segments)
    changed |= keep_farthest(outlines.chains[s.chain], std::size_t(s.i), std::size_t(s.j), outlines.tolerance_px,
                             outlines.depth_error_relative);
  if (changed) repair_crossings(outlines, fixed, face_size);
  return changed;
}

}  // namespace cellbake
