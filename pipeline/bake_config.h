// Bake configuration: a TOML file (configs/*.toml) plus `--set section.key=value`
// overrides, or command-line-only quick bakes. Unknown keys and out-of-range
// values are errors naming the file and line. Keys are documented in
// configs/plant-demo.toml and docs/configuration.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "stages/geometry.h"
#include "stages/shading.h"

namespace cellbake {

// `[cells] floors` / `bake --floors`: which of the floors `cellbake info`
// finds become bake regions (pipeline/floor_regions.h): all of them, or these
// indices (0 = the lowest). Empty: the regions are used as given.
struct FloorSelection {
  bool all = false;
  std::vector<int> indices;  // ascending, without repeats (ignored when `all`)
  bool empty() const { return !all && indices.empty(); }
};

// Parses "all", "none" (no floors: the regions as given) or a comma-separated
// list of floor indices ("0,2"). Throws
// std::runtime_error naming `what` (e.g. "--floors") and the bad word.
FloorSelection parse_floor_selection(const std::string& text, const std::string& what);

// "all" or "0,2" ("" when empty): the form parse_floor_selection reads.
std::string floor_selection_text(const FloorSelection& selection);

struct BakeConfig {
  std::filesystem::path source;  // the config file ("" for command-line only)

  // [model]
  std::filesystem::path store;   // geometry store (relative paths: to the config file)
  std::string up = "z";          // "z" or "y": the model's up axis (cell layers stack along it)
  // Whether `up` was given (model.up, --set model.up, --up). When not, a bake
  // uses the geometry store's recorded up axis (resolve_up_axis); not hashed.
  bool up_given = false;

  // [[regions]]: boxes of eye positions, model units; cells only exist inside them.
  std::vector<Box3d> regions;

  // [cells]
  double cell_size = 2.0;        // edge of a cubic view cell, model units
  // Floors whose eye layers become the regions (plan_bake, before cell ids are
  // given): `floors` of those `cellbake info` finds, eyes `eye_height` above
  // each (0: 1.7 m in the units info takes the model in: 1.7, or 170 for
  // centimetres), over the regions' horizontal extent (no regions: each
  // floor's walkable extent, as info suggests it). Not hashed or described:
  // the regions they become are.
  FloorSelection floors;
  double eye_height = 0;

  // [near]
  std::uint64_t near_budget = 100000;  // near-field triangle budget per cell (thesis: 100,000)
  // A small model's budget is this fraction of its triangles instead (never
  // under 4096, one chunk): effective_near_budget(); 0 keeps near_budget as is.
  double near_budget_fraction = 0.1;

  // [far]: how each face tile's far field is drawn (stages/far/far_choice.h):
  // "cheapest" (exact far geometry where it costs no more triangles than the
  // depth meshes it replaces), "tdm" (depth meshes only) or "geometry".
  std::string far_choice = "cheapest";
  // A far field of at most this many triangles is drawn as geometry without
  // taking samples (a depth mesh rarely costs fewer, and sampling costs time).
  std::uint64_t far_geometry_below = 256;
  // A far field whose seen geometry (what the samples saw, grown by
  // far.seen_rings, at levels where far.lod_* allow) is at most
  // far_seen_geometry_below triangles and at most far_seen_geometry_per_hit
  // triangles per pixel the samples hit is drawn as that geometry in every
  // tile, without building a depth mesh; others take the per-tile choice.
  // 0 (either): always the per-tile choice. (12.7 M plant: 0.6-1.2 M
  // triangles a cell, 0.07-0.09 per hit, which the choice drew all as
  // geometry anyway; building the meshes it weighed cost a third of the
  // bake. A field of sub-pixel triangles, where depth meshes win: ~0.9.)
  std::uint64_t far_seen_geometry_below = 2'000'000;
  double far_seen_geometry_per_hit = 0.25;
  // What the samples' rays hit is grown by this many rings of triangles
  // sharing a vertex before it stands in for depth meshes (stages/far/far_choice.h
  // grow_seen_triangles): slivers next to a hit, seen from elsewhere in the
  // cell (12.7 M plant, cells 28-36, random views: 1 ring 37.5 dB, worst view
  // 27.2, holes up to 0.47 %; 2 rings 39.2, 29.9, 0.28 %; 3 rings 40.1).
  // Rings are cheap beside samples: 4 rings with at most 8 samples beat 2
  // rings with 12 on both plants at two thirds of the cost (docs/benchmarks.md).
  int far_seen_rings = 4;
  // A tile takes exact geometry when it costs at most this many times the
  // depth-mesh triangles it replaces (geometry is exact; a view never draws
  // more than the model). At 4 the 12.7 M plant's far field is all geometry
  // (at 2 it kept 36 k depth-mesh triangles a cell, 1.5 dB worse, and cost
  // 30 % more to bake: meshing the faces it kept).
  double far_geometry_factor = 4.0;
  // The LOD tier (stages/chunk_lod.h): a far chunk may be drawn at the
  // store's coarsest simplified level whose error, seen from the nearest
  // point of the cell (or a sample), is at most this many pixels of a stored
  // cube face; 0: exact geometry only.
  double far_lod_error_px = 1.0;
  // Whether a level may replace a chunk's exact seen triangles where it costs
  // fewer (else levels only bring in chunks no tile could pay for): "auto"
  // where the chunk's triangles are thinner than a face pixel from the
  // nearest eye, so the seen triangles miss slivers other eyes see (12.7 M,
  // with factor 2 and 1 ring: 36.9 dB against 32.0 with "off"; the 2 M
  // demo: 44.5 against 46.7);
  // "on": everywhere (36.8 / 44.0); "off": nowhere.
  std::string far_lod_replaces_exact = "auto";

  // [sample]
  int face_size = 512;           // stored cube-face resolution, pixels
  int supersample = 1;           // render at face_size * supersample, box-filter down
  double near_plane = 0.01;      // model units
  // The far field reaches this many pixel footprints (at the cull box's
  // distance) inside the cull box, so that from anywhere in the cell it
  // overlaps the near field instead of leaving a seam along the box.
  double seam_shell_px = 2.0;
  // Who renders the samples (pipeline/sample_backend.h): "osmesa" | "egl" |
  // "embree" | "auto". The pixels differ between the GL rasterisers and the
  // ray caster within the parity tolerance only; the bake hash tells them apart.
  std::string sample_backend = "auto";
  // Byte cap of the Embree backend's shared BVH cache, MiB (not hashed: it
  // changes memory and speed, not pixels).
  std::uint64_t embree_cache_mb = 4096;
  // Byte cap of the decoded textures a bake holds, MiB: the GL backends' texture
  // cache per worker thread, the Embree backend's mip chains shared by all
  // (not hashed: memory and speed, not pixels).
  std::uint64_t texture_cache_mb = 512;

  // [shading]: the fixed light model every chunk drawing applies (the samples
  // bake it into their images; viewers read it back from the database's meta
  // `config`). Directions are in the up-axis frame (z = model.up); defaults
  // and meaning in stages/shading.h. "unlit" keeps vertex colours as they are.
  ShadingParams shading;

  // [samples]: where a cell's panoramic samples go (Wilson 2002 ch. 3, ch. 5)
  std::string samples_initial = "corners+centre";  // "centre" | "corners" | "corners+centre"
  double samples_void_threshold = 0.005;  // stop adding samples when the worst candidate's void is below this fraction of the sphere
  int samples_max = 8;                    // cap on samples per cell (initial set included); the 82 M plant's depth meshes were measured at 12
  int samples_void_resolution = 12;       // void rays per candidate: this^2 per cube face (16: the same PSNR at 1.8x the void rays)
  // Faces of a cell's later samples, without colour, when its first finds a
  // far field drawn all as geometry (far.seen_geometry_*): they only tell
  // which triangles are seen (0: no such samples; sample.face_size and
  // above: full size, the same rows).
  int samples_visibility_face_size = 0;
  double samples_redundancy_tolerance = 5e-5;
  int samples_keep_margin_px = 2;         // kept pixels of a delta scan grow this many rings back over removed ones
  int samples_min_island_px = 4;          // kept specks of a delta scan smaller than this are dropped (before growing)  // relative inverse-depth agreement for "an ancestor already holds this pixel"

  // [depth_mesh]
  double skin_angle_deg = 3.0;   // edges within this angle of the eye ray are skins
  double depth_jump = 0.1;       // relative depth jump beyond which an edge is a skin
  // "on": an edge is also a skin where another sample of the cell sees past its
  // midpoint (multi-source skins, stages/depth_mesh.h SkinWitness); "off": the
  // single-source tests above alone.
  std::string multi_source_skins = "on";

  // [simplify]
  // Interior vertices move only along their eye ray, by at most this much.
  double depth_error_relative = 0.01;  // relative to the depth
  // Outlines (silhouettes, skin edges, coverage edges) move at most this far
  // on screen; 0 keeps them pixel-exact (staircases, many more triangles).
  double boundary_error_px = 0.5;
  // The same for delta scans (samples other than the root); their outlines
  // mostly run along pixels an ancestor holds, which they overlap by
  // samples.keep_margin_px.
  double delta_boundary_error_px = 1.0;
  int max_face_triangles = 10000;      // per cube face (thesis VWALK cap)

  // [encode]
  std::string image_format = "avif";   // jpeg | webp | png | avif | jxl (issue #16: avif is the measured best)
  int image_quality = 55;              // 1..100 (lossy formats; 55 suits avif, jpeg used 85)
  // Face meshes: "grid" (pixel corners + log depth, blob v2) or "quantized"
  // (per-axis position_bits over the mesh bounds, blob v1).
  std::string mesh_codec = "grid";
  double mesh_depth_error = 0.001;     // grid: max relative depth error the coding adds (10 % of simplify's 1 %)
  int position_bits = 16;              // quantized: mesh position quantisation per axis

  // [view]: what a viewer (render, verify, cellbake-view) draws; not part of the bake hash
  std::uint64_t far_budget = 100000;  // far-field triangles: nearest sample + ancestors, then more samples while under this

  // [output]
  std::filesystem::path database = "cells.db";
};

// Parses a TOML config file. Throws std::runtime_error("FILE:LINE: ...") for
// syntax errors, unknown keys, wrong types and out-of-range values.
BakeConfig load_bake_config(const std::filesystem::path& file);

// Parses TOML text as if it were the file `source` (relative paths resolve
// against source's folder; messages name it).
BakeConfig parse_bake_config(std::string_view text, const std::filesystem::path& source);

// Applies one override "section.key=value" (value in TOML syntax; bare words
// are taken as strings), validating as in a file. Throws naming the override.
void apply_override(BakeConfig& config, const std::string& assignment);

// Checks cross-field rules (at least one region or a floor selection, store set).
// Throws std::runtime_error naming the config source.
void validate_bake_config(const BakeConfig& config);

// The near-field budget a bake of a model of `model_triangles` uses:
// min(near_budget, max(4096, near_budget_fraction * model_triangles)), or
// near_budget when the fraction is 0. A small model then keeps a far field
// (the thesis' 100,000 would swallow a 36 k-triangle model whole).
std::uint64_t effective_near_budget(const BakeConfig& config, std::uint64_t model_triangles);

// When config.up was not given, the store's recorded up axis (`store_up`:
// "z", "y" or "" when not recorded) replaces it. Returns a one-line note for
// the user, or "": "up axis not recorded in the store; assuming z (--up y to
// change)" when neither says, or a warning when a given axis differs from the
// recorded one (`store_up_source` says why the store has it).
std::string resolve_up_axis(BakeConfig& config, const std::string& store_up, const std::string& store_up_source);

// A canonical text form of every parameter (for hashing and the database meta).
std::string describe_bake_config(const BakeConfig& config);

// A cell database's meta `config` (describe_bake_config's text) read back
// with the same rules as a config file: every "key=value" line a known key
// with a value of its type and range, "region=x0,y0,z0,x1,y1,z1" lines six
// finite numbers with min <= max. `problems` gets one "KEY: what is wrong"
// per bad line (the line is then skipped); keys a line does not name keep
// their defaults.
struct DescribedConfig {
  BakeConfig config;
  std::vector<std::string> problems;
};
DescribedConfig config_from_description(const std::string& text);

}  // namespace cellbake
