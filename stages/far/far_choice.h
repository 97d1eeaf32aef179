// The cheapest far field per face tile (issue #13): a cell's far field is,
// tile by tile of each cube face, either the exact far geometry (the chunks
// outside the near field that the tile's frustum can see from anywhere in the
// cell, drawn whole) or the textured depth meshes of its samples (Wilson 2002
// ch. 3/5). Exact geometry has no image error, so a tile takes it whenever it
// costs no more triangles than the depth-mesh triangles it replaces; chunks
// shared by several geometry tiles count once. The tiles are the viewer's
// per-face culling grid (viewer/decoded_cell.h): a depth-mesh triangle belongs
// to a tile when its texture coordinates lie within the tile; one spanning
// tiles is dropped when every tile its texture coordinates reach draws geometry.
//
// Correctness of the mix: a dropped depth-mesh triangle lies inside its
// tiles' frusta from its sample's eye and was made of those tiles' pixels, so
// every surface it showed is among what the sample saw through them: the
// tiles' geometry (or near field, drawn anyway). Geometry is never worse
// than the depth meshes it replaces, and exact from every eye.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/geometry.h"

namespace cellbake {

enum class FarChoiceMode {
  cheapest,  // per tile, the cheaper of geometry and depth meshes (ties: geometry)
  tdm,       // depth meshes everywhere (the pre-#13 far field)
  geometry,  // exact far geometry everywhere (no samples needed)
};

// Parses "cheapest" | "tdm" | "geometry"; throws std::invalid_argument otherwise.
FarChoiceMode parse_far_choice_mode(const std::string& name);

// The tiles (bit row * kFarTiles + column) of cube face `face` through which
// some eye in `eyes` can see some point of `box`: a conservative test (each
// frustum plane against the boxes separately), so it may include tiles that
// cannot see the box but never misses one that can.
std::uint32_t tiles_seeing_box(int face, const Box3d& eyes, const Box3d& box);

// The tile (row * kFarTiles + column) whose texture-coordinate square holds
// the whole triangle, or -1 when it spans tiles.
int triangle_tile(const FaceMesh& mesh, std::size_t triangle);

struct FaceFarChoice {
  std::uint32_t geometry_tiles = 0;  // bit set: the tile draws exact geometry
  std::uint64_t tdm_triangles = 0;       // depth-mesh triangles kept, over all samples
  std::uint64_t replaced_triangles = 0;  // depth-mesh triangles dropped for geometry (within geometry tiles)
  std::uint64_t geometry_triangles = 0;  // triangles of the distinct chunks its geometry tiles need
};

// The far geometry of one source chunk: the whole chunk, some of its
// triangles, or a simplified level of the whole chunk.
struct FarPiece {
  ChunkRef chunk;
  std::vector<std::uint32_t> triangles;  // ascending; empty: the whole chunk (or its level)
  int level = 0;                         // >= 1: the store's simplified level (stages/chunk_lod.h)
  std::uint32_t level_triangles = 0;     // that level's triangles
  std::uint64_t triangle_count() const {
    return level > 0 ? level_triangles : triangles.empty() ? chunk.triangle_count : triangles.size();
  }
};

// The simplified level a far chunk may be drawn at (stages/chunk_lod.h
// choose_lod_level): level 0 when none is within the error budget.
struct FarLodChoice {
  int level = 0;
  std::uint32_t triangles = 0;
  // Whether the level may replace the chunk's exact seen triangles where it
  // costs fewer; when not, it only brings in a chunk the choice would
  // otherwise not draw at all.
  bool replaces_exact = true;
};

struct FarChoice {
  std::array<FaceFarChoice, kCubeFaces> faces;
  std::vector<FarPiece> pieces;  // the geometry drawn, by chunk id
  std::uint64_t geometry_triangles = 0;
};

// One sample as the choice reads it: per face its depth mesh and the chunks
// it saw there (CubeFace::seen).
struct FarChoiceSample {
  std::array<const FaceMesh*, kCubeFaces> meshes{};
  std::array<const std::vector<SeenChunk>*, kCubeFaces> seen{};
  // With a mesh source: a guess of each missing face's depth-mesh triangles
  // (any scale); missing meshes are asked for largest guess first.
  std::array<std::uint64_t, kCubeFaces> mesh_guess{};
};

// Chooses each face tile's representation. `far_chunks` are the chunks
// outside the near field (sorted by id; seen chunks not among them are near
// field, drawn anyway, and cost nothing). A tile's geometry is what the
// samples saw through it: the triangles that drew its pixels (SeenChunk),
// or whole chunks. Without samples every tile takes the chunks its
// frustum from `eyes` (every eye the viewer may draw the cell from) can
// reach (tiles_seeing_box), whatever `mode` says. Greedy and deterministic:
// the whole cell, then each face, then each tile takes geometry when the
// triangles it adds are no more than `geometry_factor` times the depth-mesh
// triangles it drops (exact geometry has no image error and, being part of
// the model, never makes a view draw more than the model: a factor above 1
// buys image quality with triangles), repeated until nothing changes. A
// triangle spanning tiles is dropped, and counted replaced, when all the
// tiles it reaches take geometry: it counts in the gain of the group that
// completes them. Counts only; meshes are not modified.
FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode,
                           double geometry_factor = 1.0);

// Supplies the depth mesh of face `face` of sample `sample` when the choice
// needs it (e.g. built and simplified on demand); the reference must stay
// valid until choose_far_field returns.
using FarChoiceMeshSource = std::function<const FaceMesh&(std::size_t sample, int face)>;

// The same choice when building the depth meshes is the expensive part: a
// sample's mesh pointer may be null, and `mesh_source` is then asked for it
// only when the choice depends on it. A group of tiles takes geometry as soon
// as the depth-mesh triangles known so far pay for it (more meshes can only
// add to what it drops), so a face whose tiles all end as geometry is often
// never meshed; a group that would decline asks for its missing meshes first
// (largest FarChoiceSample::mesh_guess first, then in sample and face
// order), so every decision is the one the full counts give and the geometry
// drawn is the same as with every mesh given. Faces never asked for have all
// their tiles marked geometry (also tiles with nothing to draw, so a
// depth-mesh triangle spanning into such a tile may be dropped where the
// full counts keep it: drawn the same, since no pixel centre there saw a far
// surface); their depth-mesh triangles are not counted in
// FaceFarChoice::replaced_triangles (a lower bound then). Calls
// `mesh_source` at most once per face, deterministically.
FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                           const FarChoiceMeshSource& mesh_source);

// Supplies a lower bound on the triangles of the depth mesh `mesh_source`
// would give for face `face` of sample `sample`, cheaper than the mesh (e.g.
// SimplifyResult::outline_triangles, known before refinement).
using FarChoiceBoundSource = std::function<std::uint64_t(std::size_t sample, int face)>;

// The same choice, asking first for bounds where a bound can decide: a group
// covering a face none of whose tiles is taken yet drops every triangle of
// that face, so a missing mesh counts there with its bound, and a group that
// pays with bounds takes geometry without the meshes. Meshes are asked for
// only where a bound cannot decide (a group covering part of a face, or one
// that would decline), so the choice is again the one the full counts give.
// A face whose mesh was never asked for but bounded counts its bound in
// FaceFarChoice::replaced_triangles. Calls each source at most once per
// face, deterministically (a bound, when asked, before the mesh).
//
// With `lods` (one per far chunk, in the same order; empty: none), the
// choice is made first with the levels that replace exact triangles
// (FarLodChoice::replaces_exact): such a chunk takes its level whole in
// place of its seen triangles when the level has fewer triangles than they
// are (or than the chunk, seen whole): one element covering every tile that
// saw any of it, of the level's weight. A chunk that choice draws keeps what
// it drew; the other levels then join for the chunks it does not draw, and
// the choice is made again. A level is within the error the caller allows,
// so it counts as geometry like exact triangles.
FarChoice choose_far_field(const Box3d& eyes, std::span<const ChunkRef> far_chunks,
                           std::span<const FarChoiceSample> samples, FarChoiceMode mode, double geometry_factor,
                           const FarChoiceMeshSource& mesh_source, const FarChoiceBoundSource& bound_source,
                           std::span<const FarLodChoice> lods = {});

// Which triangles use each vertex of a chunk (compressed rows: the triangles
// of vertex v are triangles[offsets[v] .. offsets[v + 1])).
struct VertexTriangles {
  std::vector<std::uint32_t> offsets, triangles;
};
VertexTriangles vertex_triangles(const Chunk& chunk);

// Grows what a face saw of `chunk` (a SeenChunk listing triangles; whole
// ones are left alone) by `rings` rings of triangles sharing a vertex, each
// added triangle taking the tiles of the seen triangles it touches. Rays
// through pixel centres miss thin slivers next to what they hit (the far
// side of a pipe, a rail's edge) that an eye elsewhere in the cell sees.
// `scratch` is reused between calls: all zero on entry (an empty vector is)
// and left all zero; it grows to the chunk's triangle count.
void grow_seen_triangles(SeenChunk& seen, const Chunk& chunk, const VertexTriangles& adjacency, int rings,
                         std::vector<std::uint16_t>& scratch);

// Removes from `mesh` the triangles whose texture coordinates lie wholly
// within tiles of `geometry_tiles` (one tile, or several spanned, all in the
// set) and the vertices only they used (order otherwise kept).
// Returns how many triangles were removed.
std::size_t drop_geometry_tiles(FaceMesh& mesh, std::uint32_t geometry_tiles);

}  // namespace cellbake
