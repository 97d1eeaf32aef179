// Which of a cell's panoramic samples a viewer draws from an eye point (Wilson
// 2002 §5.3): the sample nearest the eye plus its ancestors in the dependency
// tree (a delta scan only holds what its ancestors lack), then the next
// nearest samples with their ancestors while a far-field triangle budget
// allows.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct SampleNode {
  int index = 0;            // the sample's index in its cell
  Vec3d eye;                // world
  int parent = -1;          // index of the parent sample, -1 for the root
  std::uint64_t triangles = 0;  // what drawing the sample costs (SceneDrawer: its faces in the view frustum)
};

struct SampleSelectionParams {
  // Far-field triangles per view: the larger of far_budget and root_factor
  // times what the root sample alone costs in this view (so a cell whose
  // root is already large may still draw its delta scans). The nearest
  // sample's chain is always drawn whole.
  std::uint64_t far_budget = 100000;
  double root_factor = 2.0;
  // At most this many samples (0 = no cap). Chains are taken whole, so 1
  // draws the root (the intra scan, the only self-contained sample) alone:
  // the single-sample far field of a one-sample bake.
  int max_samples = 0;
};

// The indices of the samples to draw from `eye`, nearest chain first. Samples
// whose parent is unknown are treated as roots. Distance ties go to the lower
// index. Deterministic. Empty input gives an empty result.
std::vector<int> select_samples(const std::vector<SampleNode>& samples, const Vec3d& eye,
                                const SampleSelectionParams& params);

}  // namespace cellbake
