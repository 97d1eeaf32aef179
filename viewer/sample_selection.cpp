// Runtime sample selection for incremental textured depth meshes, Wilson 2002
// §5.3 ("we choose the scan cube whose sample location is closest to the
// user's viewpoint ... we also include the ancestors of S up to and including
// the intra scan"), with a triangle budget for further samples.
#include "viewer/sample_selection.h"

#include <algorithm>
#include <map>

namespace cellbake {

std::vector<int> select_samples(const std::vector<SampleNode>& samples, const Vec3d& eye,
                                const SampleSelectionParams& params) {
  std::map<int, const SampleNode*> by_index;
  for (const SampleNode& s : samples) by_index[s.index] = &s;
  std::vector<const SampleNode*> nearest;
  for (const SampleNode& s : samples) nearest.push_back(&s);
  std::stable_sort(nearest.begin(), nearest.end(), [&](const SampleNode* a, const SampleNode* b) {
    const double da = length(a->eye - eye), db = length(b->eye - eye);
    return da < db || (da == db && a->index < b->index);
  });
  std::uint64_t root_triangles = 0;
  for (const SampleNode& s : samples)
    if (s.parent < 0 || !by_index.contains(s.parent)) root_triangles += s.triangles;
  const double budget = std::max(double(params.far_budget), params.root_factor * double(root_triangles));
  std::vector<int> chosen;
  std::uint64_t triangles = 0;
  for (const SampleNode* s : nearest) {
    if (std::find(chosen.begin(), chosen.end(), s->index) != chosen.end()) continue;
    // The chain: the sample and every ancestor not chosen yet.
    std::vector<int> chain;
    std::uint64_t cost = 0;
    for (const SampleNode* n = s; n && chain.size() <= samples.size();) {
      if (std::find(chosen.begin(), chosen.end(), n->index) == chosen.end()) {
        chain.push_back(n->index);
        cost += n->triangles;
      }
      auto it = by_index.find(n->parent);
      n = n->parent >= 0 && it != by_index.end() ? it->second : nullptr;
    }
    // A chain that does not fit is skipped: a shorter or cheaper one further away may.
    if (params.max_samples > 0 && chosen.size() + chain.size() > std::size_t(params.max_samples)) continue;
    if (!chosen.empty() && double(triangles + cost) > budget) continue;
    chosen.insert(chosen.end(), chain.begin(), chain.end());
    triangles += cost;
  }
  return chosen;
}

}  // namespace cellbake
