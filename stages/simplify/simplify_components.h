// The region of each part of the simplifier's triangulation (simplify.cpp):
// its components, the finite faces joined across unconstrained edges, are the
// cells the outline and border constraints bound, and each takes the region
// of the dense face that holds most of it.
//
// Wilson 2002, ch. 5 §5.2.3 (each side of a silhouette keeps its own
// surface); CGAL 2D Triangulations (https://doc.cgal.org/latest/Triangulation_2/).
#pragma once

#include "stages/simplify/simplify_cdt.h"
#include "stages/simplify/simplify_outline.h"

namespace cellbake {

// Labels every finite face of `cdt` (lattice points of a face of n x n
// pixels) with the region label (`regions`) of most of the pixel centres
// inside its component's triangles; the pixel under a triangle's centroid,
// weighted by area, breaks ties and labels components too thin to hold a
// pixel centre; -1 for background. Deterministic for a given triangulation.
void label_components(Cdt& cdt, const FaceRegions& regions, int n);

}  // namespace cellbake
