// The refinement queue of the simplifier's greedy insertion (simplify.cpp
// step 3; Garland & Heckbert 1995, "Fast polygonal approximation of terrains
// and height fields"): triangulation faces by their worst depth violation,
// worst first, in a deterministic order among equal errors.
#pragma once

#include <algorithm>
#include <cstdint>
#include <tuple>
#include <vector>

#include "stages/simplify/simplify_cdt.h"
#include "stages/simplify/simplify_face_meter.h"

namespace cellbake {

// A triangle waiting in the refinement queue; stale once its face was
// destroyed or changed (the stamp no longer matches).
struct QueuedFace {
  double error = 0;
  std::uint32_t tie = 0;  // lattice index of the violating point: deterministic order among equal errors
  std::uint32_t stamp = 0;
  Cdt::Face_handle face;
  FaceViolation violation;
};

// Max-heap order: larger error first, then the smaller lattice index.
inline bool queued_before(const QueuedFace& a, const QueuedFace& b) {
  if (a.error != b.error) return a.error < b.error;
  if (a.tie != b.tie) return a.tie > b.tie;
  return a.stamp > b.stamp;
}

// Queued faces, a max-heap by queued_before.
class RefinementQueue {
 public:
  bool empty() const { return heap_.empty(); }
  // The first face in queued_before order (not empty).
  const QueuedFace& top() const { return heap_.front(); }
  void push(const QueuedFace& q) {
    heap_.push_back(q);
    std::push_heap(heap_.begin(), heap_.end(), queued_before);
  }
  // Removes top() (not empty).
  void pop() {
    std::pop_heap(heap_.begin(), heap_.end(), queued_before);
    heap_.pop_back();
  }
  void clear() { heap_.clear(); }
  // True when q's face changed since it was queued (its violation is out of date).
  static bool stale(const QueuedFace& q) { return q.face->info().stamp != q.stamp; }
  // Pops stale faces until top() is current or the queue is empty.
  void drop_stale_top() {
    while (!empty() && stale(top())) pop();
  }
  // The outline segments whose bound error exceeds `threshold` in the
  // current queued faces, sorted by (chain, i, j), each once.
  std::vector<ChainSegment> outline_segments_over(double threshold) const {
    std::vector<ChainSegment> segments;
    for (const QueuedFace& q : heap_)
      if (!stale(q) && q.violation.bound_error > threshold)
        segments.push_back({q.violation.bound_owner.chain, q.violation.bound_owner.i, q.violation.bound_owner.j});
    std::sort(segments.begin(), segments.end(), [](const ChainSegment& a, const ChainSegment& b) {
      return std::tie(a.chain, a.i, a.j) < std::tie(b.chain, b.i, b.j);
    });
    segments.erase(std::unique(segments.begin(), segments.end(),
                               [](const ChainSegment& a, const ChainSegment& b) {
                                 return a.chain == b.chain && a.i == b.i && a.j == b.j;
                               }),
                   segments.end());
    return segments;
  }

 private:
  std::vector<QueuedFace> heap_;
};

}  // namespace cellbake
