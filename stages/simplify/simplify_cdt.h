// The constrained Delaunay triangulation that simplify_face_mesh refines
// (simplify.cpp step 3): CGAL's 2D constrained Delaunay triangulation with
// exact predicates on integer lattice points (pixel-corner coordinates), each
// face carrying its region label and a stamp for the refinement queue; and
// which outline segment (or the face border) owns each constraint.
//
// CGAL 2D Triangulations (Yvinec, CGAL User and Reference Manual,
// https://doc.cgal.org/latest/Triangulation_2/); constrained Delaunay
// triangulations: Chew 1989, "Constrained Delaunay triangulations",
// Algorithmica 4.
#pragma once

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "stages/simplify/simplify_outline.h"

namespace cellbake {

using TinKernel = CGAL::Exact_predicates_inexact_constructions_kernel;
// What a triangulation face carries.
struct TinFaceInfo {
  int label = INT_MIN;      // region (-1: background; INT_MIN: not labelled yet)
  std::uint32_t stamp = 0;  // changes whenever the face is (re)made, for the refinement queue
};
using TinFaceBaseWithInfo = CGAL::Triangulation_face_base_with_info_2<TinFaceInfo, TinKernel>;
using TinFaceBase = CGAL::Constrained_triangulation_face_base_2<TinKernel, TinFaceBaseWithInfo>;
using TinTds = CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_2<TinKernel>, TinFaceBase>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<TinKernel, TinTds,
                                                       CGAL::No_constraint_intersection_requiring_constructions_tag>;
using CdtPoint = Cdt::Point;

// The lattice point of a triangulation vertex (its coordinates are integers).
inline LatticePoint lattice_of(const CdtPoint& p) { return {int(std::lround(p.x())), int(std::lround(p.y()))}; }

// Index of lattice point (x, y) of a face of n x n pixels (row-major, (n + 1)^2 points).
inline std::size_t lattice_index(int x, int y, int n) { return std::size_t(y) * (n + 1) + x; }

// Owner of a constraint: a chain segment [i, j], or the face border (chain -1).
struct ConstraintOwner {
  int chain = -1, i = 0, j = 0;
};

// The owners of a triangulation's constraints, by their end points' lattice
// indices (either order).
class ConstraintOwners {
 public:
  void clear() { owners_.clear(); }
  // Owner of the constraint between lattice points a and b; of a constraint
  // added twice, the last owner stands. Lookups wait for finish().
  void add(std::size_t a, std::size_t b, const ConstraintOwner& owner) { owners_.push_back({key(a, b), owner}); }
  // Sorts by key, dropping all but the last owner of each.
  void finish() {
    std::stable_sort(owners_.begin(), owners_.end(),
                     [](const KeyedOwner& x, const KeyedOwner& y) { return x.first < y.first; });
    std::size_t kept = 0;
    for (std::size_t i = 0; i < owners_.size(); ++i) {
      if (i + 1 < owners_.size() && owners_[i + 1].first == owners_[i].first) continue;
      owners_[kept++] = owners_[i];
    }
    owners_.resize(kept);
  }
  // The owner of the constraint between lattice points a and b, or null.
  const ConstraintOwner* find(std::size_t a, std::size_t b) const {
    const std::uint64_t k = key(a, b);
    const auto it = std::lower_bound(owners_.begin(), owners_.end(), k,
                                     [](const KeyedOwner& o, std::uint64_t key) { return o.first < key; });
    return it != owners_.end() && it->first == k ? &it->second : nullptr;
  }

 private:
  static std::uint64_t key(std::size_t a, std::size_t b) {
    return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
  }
  using KeyedOwner = std::pair<std::uint64_t, ConstraintOwner>;
  std::vector<KeyedOwner> owners_;  // by key (ascending, unique after finish())
};

}  // namespace cellbake
