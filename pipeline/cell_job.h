// The per-cell job: which stage feeds which, stage names and versions, the
// parameter/input hashes that make reruns resumable, and the assembly of a
// cell database row. The runner calls the steps in this order (sample needs
// a CubeSampler, one per thread; the others are plain CPU work):
//   step              timed as (stage_seconds) and named in errors as
//   run_cull_box      cull_box
//   run_sample        sample (its best-next-view choices also as void)
//   run_sample_tree   depth_mesh: the samples linked into their dependency tree
//   run_far_choice    far_choice, and inside it, on demand: redundancy
//                     (remove_redundancy), depth_mesh and simplify (face_mesh)
//   run_encode        encode
// No step meshes every face: the far choice removes the delta scans'
// redundant pixels, then builds and simplifies depth meshes only for the
// faces its decision depends on (a face drawn wholly as geometry is usually
// never meshed; that laziness is what keeps a bake cheap). Each stage's
// seconds are its own: the far choice's timer stops while the stages inside
// it run. A stage that throws turns the cell into a failed row whose message
// names the cell and the stage.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/cull_box.h"
#include "stages/depth_mesh.h"
#include "stages/far/far_choice.h"
#include "stages/shading.h"
#include "stages/sample/sample.h"
#include "stages/simplify/simplify.h"
#include "storage/cell_db.h"

namespace cellbake {

class CubeSampler;

// Bump a stage's version when its output changes for the same inputs: every
// cell that used it is then recomputed on the next bake.
struct StageVersions {
  static constexpr int cull_box = 1;
  static constexpr int sample = 4;      // 3: several samples per cell (initial set + best-next-view); 4: lit ([shading])
  static constexpr int depth_mesh = 2;  // 2: delta scans lose the pixels their ancestors hold
  static constexpr int simplify = 3;
  static constexpr int encode = 4;      // 2: background texels filled from their covered neighbours; 3: grid mesh codec, avif; 4: faces without triangles store no image, texels no kept triangle reads filled like background
  static constexpr int far_choice = 4;  // 1: exact far geometry per face tile where it is cheaper (issue #13); 2: depth-mesh triangles spanning geometry tiles dropped too; 3: seen triangles stored as numbers into the store's chunk; 4: faces drawn wholly as geometry are not meshed (their stored errors are 0, replaced_triangles counts meshed faces only)
};

// The stage names, in order, as used in stage_seconds and error messages.
inline constexpr std::array<const char*, 6> kStageNames = {"cull_box", "sample", "depth_mesh", "simplify", "far_choice", "encode"};

struct CellHashes {
  std::string cull;   // store content + cull_box version and parameters + the cell
  std::string input;  // cull + every later stage's version and parameters
};

// Hashes of what determines a cell's rows (not thread count, shard or timing).
CellHashes cell_hashes(const CellSpec& cell, const BakeConfig& config, const std::string& store_hash);

// The median triangle widths (stages/chunk_lod.h median_triangle_width) of a
// store's chunks, learned once per bake: every cell choosing far levels asks
// for the same chunks'. Thread-safe.
class ChunkWidths {
 public:
  // Chunk `id`'s median triangle width, loaded from `source` the first time.
  double of(std::int64_t id, const ChunkSource& source);

 private:
  std::mutex mutex_;
  std::unordered_map<std::int64_t, double> widths_;
};

// One panoramic sample of a cell in flight: taken by run_sample, linked into
// the samples' tree by run_sample_tree, reduced to its delta scan and its
// faces meshed and simplified on demand in run_far_choice, encoded.
struct SampleWork {
  CubeSample cube;
  int parent = -1;                        // dependency tree (set by run_sample_tree)
  double void_after = -1;                 // worst candidate's void fraction once this sample was taken (-1: not measured)
  std::uint64_t covered = 0, removed = 0; // pixels with a surface, and of those removed as redundant
  double seconds = 0;                     // this sample's share of the bake (render + redundancy + mesh + simplify + encode)
  bool visibility = false;                // a visibility sample (no colour, maybe smaller): replaced before any meshing
  std::array<char, kCubeFaces> meshed{};  // face meshed and simplified (face_mesh), else `simplified` is empty
  std::array<FaceMesh, kCubeFaces> simplified;
  // Faces bounded but not meshed yet (face_mesh_bound): their simplification
  // up to the outline triangulation, finished by face_mesh.
  std::array<std::unique_ptr<FaceSimplification>, kCubeFaces> pending;
  // Faces meshed while the cell had fewer than kMaxRulerFaces rulers: what
  // measuring their simplified mesh needs of the dense one, until the far
  // choice has kept or dropped them.
  std::array<SimplifyRuler, kCubeFaces> rulers;
  std::array<double, kCubeFaces> boundary_error_px{};
  std::array<double, kCubeFaces> depth_error{};
  // Its faces' depths as taken, before redundant pixels were removed: what it
  // witnesses for the other samples' multi-source skin test (empty when
  // depth_mesh.multi_source_skins is off or the cell has one sample).
  std::array<std::vector<float>, kCubeFaces> taken_depth;
};

// The work in flight for one cell, passed from stage to stage.
struct CellWork {
  CellSpec cell;
  CellHashes hashes;
  std::optional<CullBoxResult> cull;  // set by run_cull_box (or reused)
  std::vector<ChunkRef> far_chunks;   // set by run_sample: every chunk outside the near field, by id
  std::vector<SampleWork> samples;    // set by run_sample, in the order taken (none when the far field is
                                      // drawn as geometry whole: empty or under far.geometry_below triangles)
  std::optional<FarChoice> far;       // set by run_far_choice (or by run_sample: visibility_face_size)
  bool seen_grown = false;            // the samples' seen sets have grown by far.seen_rings (grow_seen_rings)
  // The chunks growing seen sets loaded, with their adjacency, kept while one
  // stage grows more than once (run_sample's visibility samples); cleared by
  // the stage.
  struct ChunkFacts {
    std::shared_ptr<const Chunk> chunk;
    VertexTriangles adjacency;
  };
  std::unordered_map<std::int64_t, ChunkFacts> chunk_facts;
  ChunkWidths* widths = nullptr;  // the bake's, when it shares one (else each width is computed when asked)
  bool redundancy_removed = false;    // remove_redundancy ran
  DepthMeshScratch depth_mesh_scratch;  // run_far_choice's memory for meshing faces one by one (freed after it)
  std::map<std::string, double> seconds;
  std::string failed_stage, error;  // set when a stage threw
  CellRow row;                      // filled by run_encode / make_failed_row
};

// Stage steps. Each fills its part of `work` and records its own seconds;
// each throws on failure (the runner catches via run_stage below).
void run_cull_box(CellWork& work, const BakeConfig& config, const ChunkSource& source);
// What a cell's samples leave to its near field: the cull box (half size
// `cull_half_size` around the cell's centre) less a shell config.seam_shell_px
// pixel footprints deep (never reaching into the cell), where the far field
// overlaps the near field.
Box3d far_field_discard_box(const Box3d& cell_bounds, double cull_half_size, const BakeConfig& config);
// The SampleParams and lights of every sample a cell takes with `config`.
SampleParams cell_sample_params(const BakeConfig& config);
ShadingLights cell_shading_lights(const BakeConfig& config);
// The depth-mesh parameters of `config` (skin angle and depth jump; no skin
// witnesses).
DepthMeshParams cell_depth_mesh_params(const BakeConfig& config);
// Takes the cell's samples with `sampler` (whichever backend it is).
void run_sample(CellWork& work, const BakeConfig& config, const ChunkSource& source, CubeSampler& sampler);
// Links the samples into their dependency tree (SampleWork::parent; timed as
// "depth_mesh", the stage whose inputs it prepares). Builds no mesh: delta
// scans are reduced to what their ancestors do not hold (remove_redundancy)
// and the faces' depth meshes built (face_mesh) later, inside run_far_choice.
void run_sample_tree(CellWork& work, const BakeConfig& config);
// Chooses exact far geometry or depth meshes per face tile and drops the
// depth-mesh triangles that geometry replaces (stages/far/far_choice.h), in
// named steps: seen triangles grown by far.seen_rings, far chunk levels
// chosen, the choice (remove_redundancy, then face_mesh_bound and face_mesh
// only for the faces the choice depends on: a face drawn wholly as geometry
// is usually never meshed), the kept meshes' errors measured, the row's far
// geometry and per-face choice written (loading the chunks it keeps
// triangles of from `source`).
void run_far_choice(CellWork& work, const BakeConfig& config, const ChunkSource& source);
// far.lod_replaces_exact = "auto": a far chunk's level replaces its exact
// seen triangles when their median width is under this many cube-face pixels
// from the nearest eye (measured at 12.7 M, cells 28-36: 1 px 36.91 dB
// median over random views, levels everywhere 36.77, never 32.00).
inline constexpr double kThinTrianglePixels = 1.0;
void run_encode(CellWork& work, const BakeConfig& config);

// The face size of the visibility samples run_sample takes after a cell's
// first when that one finds a far field drawn all as geometry (far.choice
// "cheapest" and far.seen_geometry_* set): without colour, at
// samples.visibility_face_size up to sample.face_size; 0 when that is 0 (no
// visibility samples). At sample.face_size the cell's rows are the same as
// without them.
int visibility_face_size(const BakeConfig& config);
// Grows the seen sets of samples [first, last) of `work` by far.seen_rings
// rings of neighbouring triangles (stages/far/far_choice.h
// grow_seen_triangles; each chunk's adjacency found once per cell: work.chunk_facts).
void grow_seen_rings(CellWork& work, const BakeConfig& config, const ChunkSource& source, std::size_t first,
                     std::size_t last);
// The far field drawn all as geometry when what the samples saw (their seen
// sets as they are) is at most far.seen_geometry_below triangles and
// far.seen_geometry_per_hit per pixel they hit, pixels of smaller faces
// counted at sample.face_size (far.choice "cheapest"); else nullopt.
std::optional<FarChoice> sparse_far_field(const CellWork& work, const BakeConfig& config, const ChunkSource& source);

// The stages run_far_choice runs on demand, when it needs their output.

// Reduces each delta scan to what its ancestors do not hold (timed as
// "redundancy"); once per cell, before any face is meshed.
void remove_redundancy(CellWork& work, const BakeConfig& config);
// Face `face` of sample `sample`: its dense depth mesh built and simplified
// on first use (timed as the depth_mesh and simplify stages; a failure
// throws StageError naming the stage), then kept in SampleWork::simplified.
// Its error is measured later, only if the far choice keeps some of it.
const FaceMesh& face_mesh(CellWork& work, const BakeConfig& config, std::size_t sample, int face);
// A lower bound on face_mesh's triangles for that face: the simplification's
// outline-only triangulation (SimplifyResult::outline_triangles), kept in
// SampleWork::pending so that face_mesh finishes it rather than starting over.
// At most kMaxPendingFaces faces of a cell wait so (tens of MB each); beyond
// that the face is meshed whole and its exact count returned.
std::uint64_t face_mesh_bound(CellWork& work, const BakeConfig& config, std::size_t sample, int face);
inline constexpr int kMaxPendingFaces = 8;
// At most this many faces of a cell keep a SimplifyRuler (~15 MB each) from
// face_mesh until the far choice is done.
inline constexpr int kMaxRulerFaces = 8;
// The simplifier's error for face `face` of sample `sample`, whose simplified
// mesh is still the one face_mesh made: with `ruler` when face_mesh kept one
// for the face, else by building the dense mesh again (timed as depth_mesh)
// and analysing it (timed as simplify); the same figures either way. A
// failure throws StageError naming the stage.
SimplifyError measure_face_error(CellWork& work, const BakeConfig& config, std::size_t sample, int face,
                                 const SimplifyRuler& ruler);

// A failure of a stage run inside another (a face meshed on demand by the far choice).
struct StageError : std::runtime_error {
  StageError(std::string stage_name, const std::string& message)
      : std::runtime_error(message), stage(std::move(stage_name)) {}
  std::string stage;
};

// Runs `step` for `stage` unless the cell already failed; a throw is recorded
// as "cell ID (gx,gy,gz): stage STAGE: message" (the StageError's stage when
// it names one) and later stages are skipped.
template <typename Step>
void run_stage(CellWork& work, const char* stage_name, Step&& step) {
  if (!work.failed_stage.empty()) return;
  try {
    step();
  } catch (const std::exception& e) {
    const auto* inner = dynamic_cast<const StageError*>(&e);
    const std::string stage = inner ? inner->stage : std::string(stage_name);
    work.failed_stage = stage;
    work.error = "cell " + std::to_string(work.cell.id) + " (" + std::to_string(work.cell.gx) + "," +
                 std::to_string(work.cell.gy) + "," + std::to_string(work.cell.gz) + "): stage " + stage + ": " +
                 e.what();
  }
}

// The database row for the work: the encoded cell, or a failed row with the message.
CellRow finish_cell_row(CellWork& work);

}  // namespace cellbake
