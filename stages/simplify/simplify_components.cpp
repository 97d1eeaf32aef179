// Region labels of the simplifier's triangulation components (see
// simplify_components.h; Wilson 2002, ch. 5 §5.2.3).
#include "stages/simplify/simplify_components.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <vector>

namespace cellbake {
namespace {

// Calls vote(label, count, 0) for the pixels whose centre lies in the closed
// triangle p: once per run of equal labels along a row (count: its length).
template <typename LabelFn, typename VoteFn>
void vote_pixel_centres(const std::array<LatticePoint, 3>& p, int n, LabelFn&& label, VoteFn&& vote) {
  const int ymin = std::min({p[0].y, p[1].y, p[2].y}), ymax = std::max({p[0].y, p[1].y, p[2].y});
  for (int py = std::max(ymin, 0); py < std::min(ymax, n); ++py) {
    const double y = py + 0.5;
    double xl = 1e300, xr = -1e300;
    for (int e = 0; e < 3; ++e) {
      const LatticePoint a = p[e], b = p[(e + 1) % 3];
      if ((a.y - y) * (b.y - y) > 0 || a.y == b.y) continue;
      const double x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
      xl = std::min(xl, x), xr = std::max(xr, x);
    }
    if (!(xl <= xr)) continue;
    const int x0 = std::max(0, int(std::ceil(xl - 0.5))), x1 = std::min(n - 1, int(std::floor(xr - 0.5)));
    for (int px = x0; px <= x1;) {  // one call per run of equal labels
      const int l = label(px, py);
      int end = px + 1;
      while (end <= x1 && label(end, py) == l) ++end;
      vote(l, std::size_t(end - px), 0.0);
      px = end;
    }
  }
}

}  // namespace

void label_components(Cdt& cdt, const FaceRegions& regions, int n) {
  const auto label = [&](int i, int j) { return regions.label[std::size_t(j) * n + i]; };
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info().label = INT_MIN;
  std::vector<Cdt::Face_handle> stack, members;
  struct Vote {
    int label;
    std::size_t centres;
    double area;
  };
  std::vector<Vote> votes;
  auto vote = [&](int l, std::size_t centres, double area) {
    auto it = std::find_if(votes.begin(), votes.end(), [&](const Vote& v) { return v.label == l; });
    if (it == votes.end()) votes.push_back({l, centres, area});
    else it->centres += centres, it->area += area;
  };
  for (auto start = cdt.finite_faces_begin(); start != cdt.finite_faces_end(); ++start) {
    if (start->info().label != INT_MIN) continue;
    members.clear();
    votes.clear();
    start->info().label = INT_MIN + 1;  // visiting
    stack.push_back(start);
    while (!stack.empty()) {
      const Cdt::Face_handle f = stack.back();
      stack.pop_back();
      members.push_back(f);
      const std::array<LatticePoint, 3> p{lattice_of(f->vertex(0)->point()), lattice_of(f->vertex(1)->point()),
                                          lattice_of(f->vertex(2)->point())};
      const double area =
          std::abs(double(p[1].x - p[0].x) * (p[2].y - p[0].y) - double(p[1].y - p[0].y) * (p[2].x - p[0].x));
      const int px = std::clamp(int(std::floor((p[0].x + p[1].x + p[2].x) / 3.0)), 0, n - 1);
      const int py = std::clamp(int(std::floor((p[0].y + p[1].y + p[2].y) / 3.0)), 0, n - 1);
      vote(label(px, py), 0, area);
      vote_pixel_centres(p, n, label, vote);
      for (int e = 0; e < 3; ++e) {
        const Cdt::Face_handle nb = f->neighbor(e);
        if (cdt.is_infinite(nb) || cdt.is_constrained({f, e}) || nb->info().label != INT_MIN) continue;
        nb->info().label = INT_MIN + 1;
        stack.push_back(nb);
      }
    }
    const Vote* best = &votes.front();
    for (const Vote& v : votes)
      if (v.centres > best->centres || (v.centres == best->centres && v.area > best->area)) best = &v;
    for (const Cdt::Face_handle& f : members) f->info().label = best->label;
  }
}

}  // namespace cellbake
