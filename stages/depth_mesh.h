// Dense depth meshes without skins: one triangle mesh per cube face, two
// triangles per covered pixel with corners on pixel corners.
//
// Wilson 2002, "Spatially Encoded Image-Space Simplifications for Interactive
// Walkthrough", ch. 5 §5.2.2 (dense mesh creation, corner depth = average of the
// connected neighbours) and §3.4.2.1.1 (skin heuristics).
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include "stages/cube_map.h"

namespace cellbake {

// Another sample of the same cell, as a witness for the multi-source skin
// test (§3.4.2.1.1: an edge is a skin when another sample sees past its
// midpoint): its eye and its faces' planar depths as it took them (before any
// redundant pixels were removed; faces of `size`^2, order of cube_map.h,
// kBackgroundDepth where it saw nothing).
struct SkinWitness {
  Vec3d eye;
  const std::array<std::vector<float>, kCubeFaces>* depth = nullptr;
  int size = 0;
};

struct DepthMeshParams {
  // An edge between two neighbouring pixels' surface points is a skin when the
  // angle between the edge and the eye ray through its midpoint is below this
  // (the edge is nearly parallel to the ray, i.e. it spans a depth discontinuity).
  double skin_angle_degrees = 3.0;
  // ... or when the relative jump of the eye distances, |d1 - d2| / min(d1, d2),
  // exceeds this. At 512^2 a plane must be within ~1.7 degrees of the ray before
  // its neighbouring pixels jump by 10 %.
  double max_relative_depth_jump = 0.1;
  // Multi-source skins: an edge the two tests above keep, whose relative jump
  // of eye distances exceeds `witness_min_jump`, is a skin when one of
  // `witnesses` sees past its midpoint: the witness's depths at the 3x3
  // pixels around the midpoint's projection all exceed the midpoint's own
  // planar depth there by more than `witness_margin` (relative). A block, so
  // that a surface through the midpoint — nearer than it on one side of its
  // projection — never reads as seen past; only empty space does (the wall
  // behind a thin pipe, seen past it from elsewhere in the cell). A
  // projection within a pixel of the witness's face border is not judged.
  // Empty: the single-source tests alone.
  std::vector<SkinWitness> witnesses;
  double witness_min_jump = 0.01;
  double witness_margin = 0.003;
};

struct DepthMeshStats {
  std::size_t triangles = 0;          // over all six faces
  std::size_t skin_edges = 0;         // unique neighbouring pixel pairs (8-neighbourhood, across faces too) that are skins
  std::size_t background_pixels = 0;  // over all six faces
};

// Builds one dense mesh per cube face (order of `cube_map.h`). Every pixel that
// is not background gets two triangles (NW, SW, SE) and (NW, SE, NE), counter-
// clockwise as seen from the eye. A corner vertex lies on the eye ray through the
// pixel corner; its depth interpolates the pixels around that corner that are
// connected to the pixel (the thesis' average, taken over inverse depth with a
// plane fit so that world planes give exactly coplanar corners, also across
// cube edges) (connected components of the
// 8-neighbour, non-skin adjacency among the pixels touching the corner). Corners
// on cube-face borders are computed from the pixels of every face touching them,
// so neighbouring faces get bit-identical positions there. Where a border
// corner is not fully connected (its pixels are not one component, or two pixels
// of the same face there are not directly connected, or it is next to a cube
// corner whose three pixels are not all connected), each pixel gets its own
// vertex record there (positions still shared where the surface is): this marks
// the break for `simplify_face_mesh`, which must decide border simplification
// identically on both faces.
// Positions are relative to the sample's eye (float); uv = pixel corner / size
// (u right, v down). Deterministic. Throws std::invalid_argument when the faces
// differ in size, are empty, or hold a depth that is NaN or not positive.
std::array<FaceMesh, kCubeFaces> build_depth_meshes(const CubeSample& sample, const DepthMeshParams& params,
                                                    DepthMeshStats* stats = nullptr);

// A cheap guess of how many triangles a face's simplified depth mesh needs,
// without meshing it: the pixel edges across a depth discontinuity (relative
// jump above params.max_relative_depth_jump) or between surface and
// background, where outlines (and so most simplified triangles) lie. Only
// its order matters (which face to mesh first). O(pixels).
std::uint64_t outline_edge_guess(const CubeFace& face, const DepthMeshParams& params);

// Working memory build_depth_mesh_face can keep from one call to the next
// (per-pixel buffers of one face, ~50 bytes a pixel), so meshing the faces of
// a cell one by one does not allocate and clear them each time. Holds nothing
// that changes a result; one per thread of work.
class DepthMeshScratch {
 public:
  DepthMeshScratch();
  ~DepthMeshScratch();
  DepthMeshScratch(DepthMeshScratch&&) noexcept;
  DepthMeshScratch& operator=(DepthMeshScratch&&) noexcept;
  struct Buffers;
  Buffers& buffers();

 private:
  std::unique_ptr<Buffers> buffers_;
};

// Face `face` alone of build_depth_meshes(sample, params), bit for bit (a
// face's border corners read its neighbours' pixels, not their meshes), for
// callers that mesh only the faces they need, with `scratch`'s memory when
// given. Throws as build_depth_meshes.
FaceMesh build_depth_mesh_face(const CubeSample& sample, const DepthMeshParams& params, int face,
                               DepthMeshScratch* scratch = nullptr);

}  // namespace cellbake
