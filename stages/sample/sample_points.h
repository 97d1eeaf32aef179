// Where a view cell's panoramic samples are taken, and how they depend on each
// other (Wilson 2002, ch. 3 and §5.2.1): an initial set of sample points in the
// cell's navigable part, and the dependency tree over the samples that guides
// redundant-point removal (intra scan = root, delta scans below it).
#pragma once

#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

enum class InitialSamples { centre, corners, corners_centre };

// Parses "centre" | "corners" | "corners+centre". Throws std::invalid_argument
// naming the accepted values for anything else.
InitialSamples parse_initial_samples(const std::string& text);
const char* initial_samples_name(InitialSamples kind);

// The navigable part of a cell: its bounds intersected with its region box.
// A region thinner than the cell along an axis (a floor slab at eye height)
// gives a navigable part that is flat along that axis. Returns an empty box
// when they do not meet.
Box3d navigable_part(const Box3d& cell, const Box3d& region);

// The initial sample points of a navigable part: its centre and/or its
// distinct corners (4 for a flat rectangle, 2 for a segment, 8 for a box; a
// point gives itself once). Order: centre first (when asked), then corners in
// (x, y, z) bit order. Deterministic; duplicates are dropped. Throws
// std::invalid_argument for an empty or non-finite box.
std::vector<Vec3d> initial_sample_points(const Box3d& navigable, InitialSamples kind);

// The dependency tree over sample points: parent[i] is the index of sample i's
// parent, -1 for the root. The root (intra scan) is the sample nearest the
// centroid of all points (ties: lowest index). The rest hang from it by a
// shortest-path tree over the complete graph with edge weight distance^3 — the
// weight the thesis gives so that trees are deeper than a star (§5.2.1; its
// text says "minimum spanning tree", but a spanning tree is invariant under a
// monotone weight, so the described effect only exists for shortest paths).
// Ties go to the lower index. Empty input gives an empty result.
std::vector<int> sample_dependency_tree(const std::vector<Vec3d>& points);

// The ancestors of sample i, nearest first (parent, grandparent, ..., root).
std::vector<int> sample_ancestors(const std::vector<int>& parent, int i);

}  // namespace cellbake
