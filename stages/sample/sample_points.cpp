// Initial sample points and the sample dependency tree, Wilson 2002 ch. 3
// (sample placement) and §5.2.1 (intra scan, delta scans, dependency tree).
#include "stages/sample/sample_points.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace cellbake {

InitialSamples parse_initial_samples(const std::string& text) {
  if (text == "centre" || text == "center") return InitialSamples::centre;
  if (text == "corners") return InitialSamples::corners;
  if (text == "corners+centre" || text == "corners+center") return InitialSamples::corners_centre;
  throw std::invalid_argument("samples.initial must be \"centre\", \"corners\" or \"corners+centre\", got \"" + text +
                              "\"");
}

const char* initial_samples_name(InitialSamples kind) {
  switch (kind) {
    case InitialSamples::centre: return "centre";
    case InitialSamples::corners: return "corners";
    default: return "corners+centre";
  }
}

Box3d navigable_part(const Box3d& cell, const Box3d& region) {
  Box3d out;
  for (int a = 0; a < 3; ++a) {
    out.lo[a] = std::max(cell.lo[a], region.lo[a]);
    out.hi[a] = std::min(cell.hi[a], region.hi[a]);
  }
  return out.empty() ? Box3d{} : out;
}

std::vector<Vec3d> initial_sample_points(const Box3d& box, InitialSamples kind) {
  if (box.empty() || !is_finite(box.lo) || !is_finite(box.hi))
    throw std::invalid_argument("sample points: the navigable part of the cell is empty or not finite");
  std::vector<Vec3d> points;
  const auto add = [&](const Vec3d& p) {
    for (const Vec3d& q : points)
      if (q == p) return;
    points.push_back(p);
  };
  if (kind != InitialSamples::corners) add(box.center());
  if (kind != InitialSamples::centre)
    for (int c = 0; c < 8; ++c)
      add({c & 1 ? box.hi.x : box.lo.x, c & 2 ? box.hi.y : box.lo.y, c & 4 ? box.hi.z : box.lo.z});
  return points;
}

std::vector<int> sample_dependency_tree(const std::vector<Vec3d>& points) {
  const int n = static_cast<int>(points.size());
  std::vector<int> parent(points.size(), -1);
  if (n == 0) return parent;
  Vec3d centroid;
  for (const Vec3d& p : points) centroid = centroid + p * (1.0 / n);
  int root = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const double d = length(points[i] - centroid);
    if (d < best) best = d, root = i;
  }
  // Dijkstra on the complete graph (n is small: at most a few dozen samples).
  std::vector<double> cost(points.size(), std::numeric_limits<double>::infinity());
  std::vector<bool> done(points.size(), false);
  cost[root] = 0;
  for (int round = 0; round < n; ++round) {
    int u = -1;
    for (int i = 0; i < n; ++i)
      if (!done[i] && (u < 0 || cost[i] < cost[u])) u = i;
    done[u] = true;
    for (int v = 0; v < n; ++v) {
      if (done[v]) continue;
      const double d = length(points[v] - points[u]);
      const double c = cost[u] + d * d * d;
      if (c < cost[v] || (c == cost[v] && u < parent[v])) cost[v] = c, parent[v] = u;
    }
  }
  return parent;
}

std::vector<int> sample_ancestors(const std::vector<int>& parent, int i) {
  std::vector<int> out;
  for (int p = parent.at(i); p >= 0 && out.size() < parent.size(); p = parent.at(p)) out.push_back(p);
  return out;
}

}  // namespace cellbake
