#include "pipeline/cell_job.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <map>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "pipeline/sample_backend.h"
#include "stages/background_fill.h"
#include "stages/chunk_lod.h"
#include "stages/chunk_subset.h"
#include "stages/sample/cube_sampler.h"
#include "stages/depth_mesh.h"
#include "stages/encode/encode.h"
#include "stages/encode/encode_triangle_list.h"
#include "stages/hashing.h"
#include "stages/sample/sample.h"
#include "stages/sample/sample_candidates.h"
#include "stages/sample/sample_points.h"
#include "stages/sample/sample_redundancy.h"
#include "stages/sample/sample_void.h"
#include "stages/simplify/simplify.h"
#include "storage/cell_content_hash.h"

namespace cellbake {
namespace {

// far.lod_replaces_exact = "auto": a far chunk's level replaces its exact
// seen triangles when their median width is under this many cube-face pixels
// from the nearest eye (measured at 12.7 M, cells 28-36: 1 px 36.91 dB
// median over random views, levels everywhere 36.77, never 32.00).
constexpr double kThinTrianglePixels = 1.0;

// Which of work.far_chunks (sorted by id) some sample saw, by index.
std::vector<char> seen_far_chunks(const CellWork& work) {
  std::vector<char> seen(work.far_chunks.size(), 0);
  for (const SampleWork& s : work.samples)
    for (const CubeFace& face : s.cube.faces)
      for (const SeenChunk& c : face.seen) {
        const auto it = std::lower_bound(work.far_chunks.begin(), work.far_chunks.end(), c.id,
                                         [](const ChunkRef& r, std::int64_t v) { return r.id < v; });
        if (it != work.far_chunks.end() && it->id == c.id) seen[std::size_t(it - work.far_chunks.begin())] = 1;
      }
  return seen;
}

using Clock = std::chrono::steady_clock;

// Adds the seconds from its construction to its destruction to the cell's
// `stage`, less those spent in pause_during: a stage's own time, without the
// stages it runs inside it (which time themselves).
class StageTimer {
 public:
  StageTimer(CellWork& work, const char* stage) : work_(work), stage_(stage), start_(Clock::now()) {}
  ~StageTimer() { stop(); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

  // Runs `nested` (a stage that times itself) with this timer stopped, and
  // returns what it returns.
  template <typename Nested>
  decltype(auto) pause_during(Nested&& nested) {
    stop();
    const Restart restart{*this};
    return std::forward<Nested>(nested)();
  }

 private:
  struct Restart {
    StageTimer& timer;
    ~Restart() { timer.start_ = Clock::now(), timer.running_ = true; }
  };
  void stop() {
    if (running_) work_.seconds[stage_] += std::chrono::duration<double>(Clock::now() - start_).count();
    running_ = false;
  }

  CellWork& work_;
  const char* stage_;
  Clock::time_point start_;
  bool running_ = true;
};

DepthMeshParams depth_mesh_params(const BakeConfig& config) {
  DepthMeshParams p;
  p.skin_angle_degrees = config.skin_angle_deg;
  p.max_relative_depth_jump = config.depth_jump;
  return p;
}

// The parameters for meshing sample `i` of `work`: every other sample that
// kept its depths as taken is a skin witness.
DepthMeshParams depth_mesh_params(const BakeConfig& config, const CellWork& work, std::size_t i) {
  DepthMeshParams p = depth_mesh_params(config);
  for (std::size_t k = 0; k < work.samples.size(); ++k)
    if (k != i && !work.samples[k].taken_depth[0].empty())
      p.witnesses.push_back({work.samples[k].cube.eye, &work.samples[k].taken_depth, work.samples[k].cube.faces[0].size});
  return p;
}

void hash_vec(Hasher& h, const Vec3d& v) { h.f64(v.x).f64(v.y).f64(v.z); }

void hash_box(Hasher& h, const Box3d& b) {
  h.f64(b.lo.x).f64(b.lo.y).f64(b.lo.z).f64(b.hi.x).f64(b.hi.y).f64(b.hi.z);
}

}  // namespace

CellHashes cell_hashes(const CellSpec& cell, const BakeConfig& c, const std::string& store_hash) {
  Hasher cull;
  cull.text("cull_box").u64(StageVersions::cull_box).text(store_hash);
  hash_box(cull, cell.bounds);
  cull.u64(c.near_budget);
  CellHashes h;
  h.cull = cull.hex();
  Hasher in;
  in.text(h.cull);
  in.text("sample").u64(StageVersions::sample).u64(c.face_size).u64(c.supersample).f64(c.near_plane);
  in.f64(c.seam_shell_px);
  // Only the ray caster's pixels are told apart, so bakes from before the
  // backend choice (GL) keep their hashes.
  if (const std::string pixels = sample_backend_pixels(parse_sample_backend(c.sample_backend)); pixels != "gl")
    in.text("backend").text(pixels);
  in.text(shading_mode_name(c.shading.mode));
  hash_vec(in, c.shading.key_direction);
  hash_vec(in, c.shading.fill_direction);
  in.f64(c.shading.key_strength).f64(c.shading.fill_strength).f64(c.shading.ambient);
  // Lit samples take the lights in the up-axis frame (z keeps the hash it had).
  if (c.up != "z" && c.shading.mode != ShadingMode::unlit) in.text("up").text(c.up);
  in.text("samples").text(c.samples_initial).f64(c.samples_void_threshold).u64(c.samples_max);
  in.u64(c.samples_void_resolution);
  in.f64(c.samples_redundancy_tolerance).u64(c.samples_keep_margin_px).f64(c.delta_boundary_error_px);
  in.u64(c.samples_min_island_px);
  // Where the samples may go: the cell's navigable part (not the whole region,
  // so growing a region leaves its existing cells up to date).
  if (cell.region >= 0 && std::size_t(cell.region) < c.regions.size())
    hash_box(in, navigable_part(cell.bounds, c.regions[std::size_t(cell.region)]));
  in.text("depth_mesh").u64(StageVersions::depth_mesh).f64(c.skin_angle_deg).f64(c.depth_jump);
  if (c.multi_source_skins != "off") in.text("multi_source_skins").text(c.multi_source_skins);
  in.text("simplify").u64(StageVersions::simplify).f64(c.depth_error_relative).f64(c.boundary_error_px).u64(c.max_face_triangles);
  in.text("encode").u64(StageVersions::encode).text(c.image_format).u64(c.image_quality).u64(c.position_bits)
      .text(c.mesh_codec).f64(c.mesh_depth_error);
  in.text("far_choice").u64(StageVersions::far_choice).text(c.far_choice).u64(c.far_geometry_below);
  if (c.far_seen_rings != 0) in.text("seen_rings").u64(std::uint64_t(c.far_seen_rings));
  in.text("geometry_factor").f64(c.far_geometry_factor);
  if (c.far_lod_error_px != 0) in.text("lod_error_px").f64(c.far_lod_error_px);
  if (c.far_seen_geometry_below != 0 && c.far_seen_geometry_per_hit > 0)
    in.text("seen_geometry_below").u64(c.far_seen_geometry_below).f64(c.far_seen_geometry_per_hit);
  if (c.far_lod_error_px != 0 && c.far_lod_replaces_exact == "on") in.text("lod_replaces_exact");
  if (c.far_lod_error_px != 0 && c.far_lod_replaces_exact == "auto")
    in.text("lod_replaces_exact").text(c.far_lod_replaces_exact).f64(kThinTrianglePixels);
  h.input = in.hex();
  return h;
}

void run_cull_box(CellWork& work, const BakeConfig& config, const ChunkSource& source) {
  if (work.cull) return;  // reused from the database: same cull hash
  StageTimer timer(work, "cull_box");
  CullBoxParams p;
  p.triangle_budget = config.near_budget;
  p.min_half_size = work.cell.half_size();
  work.cull = find_cull_box(work.cell.center(), p, source);
}


Box3d far_field_discard_box(const Box3d& cell_bounds, double cull_half_size, const BakeConfig& config) {
  const double footprint = 2.0 * cull_half_size / config.face_size;
  const double cell_half_size = 0.5 * (cell_bounds.hi.x - cell_bounds.lo.x);
  const double shell = std::clamp(config.seam_shell_px * footprint, 0.0, std::max(0.0, cull_half_size - cell_half_size));
  return Box3d::cube(cell_bounds.center(), cull_half_size - shell);
}

SampleParams cell_sample_params(const BakeConfig& config) {
  SampleParams p;
  p.face_size = config.face_size;
  p.supersample = config.supersample;
  p.near_plane = config.near_plane;
  return p;
}

ShadingLights cell_shading_lights(const BakeConfig& config) {
  return shading_lights(config.shading, config.up == "y" ? Vec3d{0, 1, 0} : Vec3d{0, 0, 1});
}

void run_sample(CellWork& work, const BakeConfig& config, const ChunkSource& source, CubeSampler& sampler) {
  StageTimer timer(work, "sample");
  sampler.set_shading(cell_shading_lights(config));
  const SampleParams p = cell_sample_params(config);
  const Box3d discard_box = far_field_discard_box(work.cell.bounds, work.cull->half_size, config);
  Box3d nav = work.cell.bounds;
  if (work.cell.region >= 0 && std::size_t(work.cell.region) < config.regions.size())
    nav = navigable_part(work.cell.bounds, config.regions[std::size_t(work.cell.region)]);
  if (nav.empty()) nav = Box3d::cube(work.cell.center(), 0);
  // The far field's chunks: a far field drawn as geometry whole needs no samples.
  work.far_chunks.clear();
  std::uint64_t far_triangles = 0;
  {
    std::vector<std::int64_t> near;
    for (const auto& n : work.cull->near_field) near.push_back(n.chunk_id);
    std::sort(near.begin(), near.end());
    for (const ChunkRef& c : source.query(source.model_bounds()))
      if (!std::binary_search(near.begin(), near.end(), c.id)) {
        work.far_chunks.push_back(c);
        far_triangles += c.triangle_count;
      }
  }
  work.samples.clear();
  const FarChoiceMode mode = parse_far_choice_mode(config.far_choice);
  if (mode == FarChoiceMode::geometry || (mode == FarChoiceMode::cheapest && far_triangles <= config.far_geometry_below))
    return;
  std::vector<Vec3d> points = initial_sample_points(nav, parse_initial_samples(config.samples_initial));
  if (points.size() > std::size_t(config.samples_max)) points.resize(std::size_t(config.samples_max));
  const auto take = [&](const Vec3d& eye) {
    const auto t0 = Clock::now();
    SampleWork s;
    s.cube = sampler.sample(eye, discard_box, p, source);
    s.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    work.samples.push_back(std::move(s));
  };
  for (const Vec3d& eye : points) take(eye);
  // Best next view: the candidate that sees the most void, while it sees enough.
  VoidParams vp;
  vp.face_size = config.samples_void_resolution;
  vp.step_ratio = 0.05;  // measured on the demo plant: the same sample choices as 0.03 at ~60 % of the time
  vp.max_distance = length(source.model_bounds().extent()) + length(discard_box.extent());
  // Candidates recur after a sample is added (Voronoi vertices away from it):
  // their rays seen for good are not marched again (the same scores).
  const auto bits_less = [](const Vec3d& a, const Vec3d& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  };
  std::map<Vec3d, VoidRayMemory, decltype(bits_less)> memories(bits_less);
  while (true) {
    const auto t0 = Clock::now();
    std::vector<Vec3d> eyes;
    for (const SampleWork& s : work.samples) eyes.push_back(s.cube.eye);
    const std::vector<Vec3d> candidates = next_view_candidates(nav, eyes);
    std::vector<VoidSample> existing;
    for (const SampleWork& s : work.samples) existing.push_back({&s.cube});
    double worst = 0;
    std::optional<Vec3d> next;
    for (const Vec3d& c : candidates) {
      const double v = void_fraction(c, existing, vp, memories[c]).fraction;
      if (v > worst) worst = v, next = c;  // candidates come sorted: ties keep the first
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    work.seconds["void"] += seconds;
    work.samples.back().void_after = worst;
    if (!next || worst < config.samples_void_threshold || work.samples.size() >= std::size_t(config.samples_max)) break;
    take(*next);
    work.samples.back().seconds += seconds;
  }
}

void run_sample_tree(CellWork& work, const BakeConfig& /*config: the meshing keys are read on demand*/) {
  StageTimer timer(work, "depth_mesh");
  std::vector<Vec3d> eyes;
  for (const SampleWork& s : work.samples) eyes.push_back(s.cube.eye);
  const std::vector<int> parent = sample_dependency_tree(eyes);
  for (std::size_t i = 0; i < work.samples.size(); ++i) work.samples[i].parent = parent[i];
  work.redundancy_removed = false;
}

void remove_redundancy(CellWork& work, const BakeConfig& config) {
  if (work.redundancy_removed) return;
  work.redundancy_removed = true;
  StageTimer timer(work, "redundancy");
  std::vector<int> parent(work.samples.size());
  for (std::size_t i = 0; i < work.samples.size(); ++i) parent[i] = work.samples[i].parent;
  // Delta scans lose what their ancestors hold. Ancestors are read unmodified,
  // so samples are reduced deepest first (all of a sample's descendants are
  // deeper than it).
  std::vector<std::size_t> order(work.samples.size());
  std::vector<std::size_t> depth(work.samples.size(), 0);
  for (std::size_t i = 0; i < order.size(); ++i) {
    order[i] = i;
    depth[i] = sample_ancestors(parent, int(i)).size();
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return depth[a] > depth[b]; });
  RedundancyParams rp;
  rp.tolerance = config.samples_redundancy_tolerance;
  rp.jump = config.depth_jump;
  rp.keep_margin = config.samples_keep_margin_px;
  rp.min_island = config.samples_min_island_px;
  if (config.multi_source_skins != "off" && work.samples.size() > 1)
    for (SampleWork& s : work.samples)
      for (int f = 0; f < kCubeFaces; ++f) s.taken_depth[std::size_t(f)] = s.cube.faces[std::size_t(f)].depth;
  for (std::size_t i : order) {
    const auto t0 = Clock::now();
    std::vector<const CubeSample*> ancestors;
    for (int a : sample_ancestors(parent, int(i))) ancestors.push_back(&work.samples[std::size_t(a)].cube);
    const RedundancyStats st = remove_redundant_pixels(work.samples[i].cube, ancestors, rp);
    work.samples[i].covered = st.covered;
    work.samples[i].removed = st.removed;
    work.samples[i].seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
}

namespace {

std::string face_where(std::size_t sample, int face) {
  return "sample " + std::to_string(sample) + " face " + std::to_string(face) + ": ";
}

// The simplification of a face up to its outline triangulation (timed as the
// depth_mesh and simplify stages).
std::unique_ptr<FaceSimplification> start_face_simplification(CellWork& work, const BakeConfig& config,
                                                              std::size_t sample, int face) {
  remove_redundancy(work, config);
  SampleWork& s = work.samples.at(sample);
  const std::string where = face_where(sample, face);
  FaceMesh dense;
  {
    const auto t0 = Clock::now();
    StageTimer timer(work, "depth_mesh");
    try {
      dense = build_depth_mesh_face(s.cube, depth_mesh_params(config, work, sample), face, &work.depth_mesh_scratch);
    } catch (const std::exception& e) {
      throw StageError("depth_mesh", where + e.what());
    }
    s.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  const auto t0 = Clock::now();
  StageTimer timer(work, "simplify");
  SimplifyParams p;
  p.depth_error_relative = config.depth_error_relative;
  p.boundary_error_px = s.parent < 0 ? config.boundary_error_px : config.delta_boundary_error_px;
  p.max_triangles = static_cast<std::size_t>(config.max_face_triangles);
  p.measure_error = false;  // measured after the far choice, for the meshes kept (drop_replaced_and_measure_kept)
  std::unique_ptr<FaceSimplification> started;
  try {
    started = std::make_unique<FaceSimplification>(std::move(dense), config.face_size, p);
  } catch (const std::exception& e) {
    throw StageError("simplify", where + e.what());
  }
  s.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  return started;
}

// Faces of the cell that hold something in `slots` (SampleWork::pending or
// SampleWork::rulers).
template <typename Slots>
int faces_holding(const CellWork& work, Slots SampleWork::*slots) {
  int n = 0;
  for (const SampleWork& s : work.samples)
    for (const auto& held : s.*slots) n += bool(held);
  return n;
}

}  // namespace

const FaceMesh& face_mesh(CellWork& work, const BakeConfig& config, std::size_t sample, int face) {
  SampleWork& s = work.samples.at(sample);
  const std::size_t f = std::size_t(face);
  if (s.meshed.at(f)) return s.simplified[f];
  std::unique_ptr<FaceSimplification> started = std::move(s.pending[f]);
  if (!started) started = start_face_simplification(work, config, sample, face);
  const auto t0 = Clock::now();
  StageTimer timer(work, "simplify");
  try {
    // Up to kMaxRulerFaces faces of the cell keep their dense mesh's analysis
    // to be measured without building it again.
    SimplifyResult r = faces_holding(work, &SampleWork::rulers) < kMaxRulerFaces
                           ? std::move(*started).finish(s.rulers[f])
                           : std::move(*started).finish();
    s.simplified[f] = std::move(r.mesh);
  } catch (const std::exception& e) {
    throw StageError("simplify", face_where(sample, face) + e.what());
  }
  s.meshed[f] = 1;
  s.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  return s.simplified[f];
}

std::uint64_t face_mesh_bound(CellWork& work, const BakeConfig& config, std::size_t sample, int face) {
  SampleWork& s = work.samples.at(sample);
  const std::size_t f = std::size_t(face);
  if (s.meshed.at(f)) return s.simplified[f].triangle_count();
  if (!s.pending[f]) {
    if (faces_holding(work, &SampleWork::pending) >= kMaxPendingFaces)
      return face_mesh(work, config, sample, face).triangle_count();
    s.pending[f] = start_face_simplification(work, config, sample, face);
  }
  return s.pending[f]->outline_triangles();
}

namespace {

// The simplifier's error for face `face` of sample `sample`, whose simplified
// mesh is still the one face_mesh made: with the face's ruler when face_mesh
// kept one, else by building the dense mesh again (timed as depth_mesh) and
// analysing it (timed as simplify); the same figures either way.
SimplifyError measure_face_error(CellWork& work, const BakeConfig& config, std::size_t sample, int face,
                                 const SimplifyRuler& ruler) {
  const SampleWork& s = work.samples[sample];
  const std::size_t k = std::size_t(face);
  const std::string where = face_where(sample, face);
  FaceMesh dense;
  if (!ruler) {
    StageTimer timer(work, "depth_mesh");
    try {
      dense = build_depth_mesh_face(s.cube, depth_mesh_params(config, work, sample), face, &work.depth_mesh_scratch);
    } catch (const std::exception& e) {
      throw StageError("depth_mesh", where + e.what());
    }
  }
  StageTimer timer(work, "simplify");
  try {
    return ruler ? ruler.measure(s.simplified[k])
                 : measure_simplification_error(dense, s.simplified[k], config.face_size);
  } catch (const std::exception& e) {
    throw StageError("simplify", where + e.what());
  }
}

// Drops the depth-mesh triangles geometry tiles replace, and measures the
// simplifier's error (stored with each face) for the faces that keep some,
// against the simplified mesh as it was before the drop (measure_face_error,
// run with `own_time` paused). Faces drawn wholly as geometry store no mesh
// and no error.
void drop_replaced_and_measure_kept(CellWork& work, const BakeConfig& config, StageTimer& own_time) {
  for (std::size_t i = 0; i < work.samples.size(); ++i) {
    SampleWork& s = work.samples[i];
    for (int f = 0; f < kCubeFaces; ++f) {
      const std::size_t k = std::size_t(f);
      const SimplifyRuler ruler = std::move(s.rulers[k]);  // freed once this face is done
      s.boundary_error_px[k] = s.depth_error[k] = 0;
      FaceMesh kept = s.simplified[k];
      drop_geometry_tiles(kept, work.far->faces[k].geometry_tiles);
      if (kept.triangle_count() == 0) {
        s.simplified[k] = FaceMesh{};
        continue;
      }
      const SimplifyError e = own_time.pause_during([&] { return measure_face_error(work, config, i, f, ruler); });
      s.boundary_error_px[k] = e.max_boundary_error_px;
      s.depth_error[k] = e.max_depth_error_relative;
      s.simplified[k] = std::move(kept);
    }
  }
}

// What the samples saw, grown by far.seen_rings rings of neighbouring
// triangles (each chunk's adjacency built once per cell).
void grow_seen_rings(CellWork& work, const BakeConfig& config, const ChunkSource& source) {
  if (config.far_seen_rings <= 0) return;
  std::unordered_map<std::int64_t, std::pair<std::shared_ptr<const Chunk>, VertexTriangles>> chunks;
  std::vector<std::uint16_t> scratch;
  for (SampleWork& s : work.samples)
    for (CubeFace& face : s.cube.faces)
      for (SeenChunk& seen : face.seen) {
        if (seen.whole()) continue;
        auto it = chunks.find(seen.id);
        if (it == chunks.end()) {
          std::shared_ptr<const Chunk> chunk = source.load(seen.id);
          VertexTriangles adjacency = vertex_triangles(*chunk);
          it = chunks.emplace(seen.id, std::make_pair(std::move(chunk), std::move(adjacency))).first;
        }
        grow_seen_triangles(seen, *it->second.first, it->second.second, config.far_seen_rings, scratch);
      }
}

// Every eye the viewer may draw the cell from: the cell, and the samples in it.
Box3d viewer_eyes(const CellWork& work) {
  Box3d eyes = work.cell.bounds;
  for (const SampleWork& s : work.samples) eyes.expand(s.cube.eye);
  return eyes;
}

// Each far chunk's coarsest stored level within far.lod_error_px, seen from
// the nearest of `eyes`, and whether it may replace the chunk's exact seen
// triangles (far.lod_replaces_exact; "auto": where the chunk's triangles are
// thinner than the pixel rays that found them, so what the samples hit may
// miss what other eyes see). Empty when far.lod_error_px is 0.
std::vector<FarLodChoice> choose_far_levels(const CellWork& work, const BakeConfig& config, const ChunkSource& source,
                                            const Box3d& eyes) {
  std::vector<FarLodChoice> lods;
  if (config.far_lod_error_px <= 0) return lods;
  lods.resize(work.far_chunks.size());
  std::vector<char> seen;
  if (config.far_lod_replaces_exact == "auto") seen = seen_far_chunks(work);
  for (std::size_t i = 0; i < work.far_chunks.size(); ++i) {
    const std::vector<ChunkLodRef> levels = source.lods(work.far_chunks[i].id);
    if (levels.empty()) continue;
    const double distance = box_distance(eyes, work.far_chunks[i].bounds);
    const double allowed = allowed_lod_error(distance, config.far_lod_error_px, config.face_size);
    lods[i].level = choose_lod_level(levels, allowed);
    if (lods[i].level == 0) continue;
    for (const ChunkLodRef& l : levels)
      if (l.level == lods[i].level) lods[i].triangles = l.triangle_count;
    if (config.far_lod_replaces_exact == "off")
      lods[i].replaces_exact = false;
    else if (config.far_lod_replaces_exact == "auto")
      lods[i].replaces_exact =
          seen[i] && seen_subset_may_miss(median_triangle_width(*source.load(work.far_chunks[i].id)), distance,
                                          kThinTrianglePixels, config.face_size);
  }
  return lods;
}

// What the samples saw, drawn as geometry in every tile, when it is at most
// far.seen_geometry_below triangles and far.seen_geometry_per_hit per pixel
// the samples hit (else nullopt): no depth mesh is built, nor the delta scans
// reduced. Triangles that each cover several pixels are what the per-tile
// choice takes anyway (12.7 M plant: 0.07-0.09 per hit, all geometry at
// factor 4); a field of sub-pixel triangles (about 1 per hit) is where depth
// meshes win, and there the per-tile choice decides.
std::optional<FarChoice> sparse_seen_far_field(const CellWork& work, const BakeConfig& config, const Box3d& eyes,
                                               std::span<const FarLodChoice> lods) {
  if (config.far_seen_geometry_below == 0 || config.far_seen_geometry_per_hit <= 0 || work.samples.empty())
    return std::nullopt;
  std::vector<FarChoiceSample> seen_only(work.samples.size());
  for (std::size_t i = 0; i < work.samples.size(); ++i)
    for (int f = 0; f < kCubeFaces; ++f)
      seen_only[i].seen[std::size_t(f)] = &work.samples[i].cube.faces[std::size_t(f)].seen;
  const auto no_mesh = [](std::size_t, int) -> const FaceMesh& {
    throw std::logic_error("far choice: a face mesh was asked for an all-geometry far field");
  };
  FarChoice all = choose_far_field(eyes, work.far_chunks, seen_only, FarChoiceMode::geometry,
                                   config.far_geometry_factor, no_mesh, FarChoiceBoundSource{}, lods);
  if (all.geometry_triangles > config.far_seen_geometry_below) return std::nullopt;
  std::uint64_t hits = 0;  // pixels of the samples that saw a far surface
  for (const SampleWork& s : work.samples)
    for (const CubeFace& face : s.cube.faces)
      for (const float d : face.depth) hits += d < kBackgroundDepth;
  if (double(all.geometry_triangles) > config.far_seen_geometry_per_hit * double(hits)) return std::nullopt;
  return all;
}

// The samples as the far choice reads them: the faces meshed so far, what
// each face saw, and for the others a guess of their mesh's size.
std::vector<FarChoiceSample> far_choice_samples(const CellWork& work, const BakeConfig& config) {
  const DepthMeshParams mesh_params = depth_mesh_params(config);
  std::vector<FarChoiceSample> samples;
  for (const SampleWork& s : work.samples) {
    FarChoiceSample c;
    for (int f = 0; f < kCubeFaces; ++f) {
      c.meshes[std::size_t(f)] = s.meshed[std::size_t(f)] ? &s.simplified[std::size_t(f)] : nullptr;
      c.seen[std::size_t(f)] = &s.cube.faces[std::size_t(f)].seen;
      if (!c.meshes[std::size_t(f)])
        c.mesh_guess[std::size_t(f)] = outline_edge_guess(s.cube.faces[std::size_t(f)], mesh_params);
    }
    samples.push_back(c);
  }
  return samples;
}

// Sets work.far: all geometry where the samples saw little (far.choice
// "cheapest", sparse_seen_far_field), else the per-tile choice
// (stages/far/far_choice.h) once the delta scans lost their redundant pixels,
// meshing and simplifying faces on demand. The nested stages (redundancy,
// depth_mesh, simplify) time themselves, with `own_time` paused.
void choose_far(CellWork& work, const BakeConfig& config, const Box3d& eyes, std::span<const FarLodChoice> lods,
                StageTimer& own_time) {
  const FarChoiceMode mode = parse_far_choice_mode(config.far_choice);
  if (mode == FarChoiceMode::cheapest) work.far = sparse_seen_far_field(work, config, eyes, lods);
  if (work.far) return;
  own_time.pause_during([&] { remove_redundancy(work, config); });
  const std::vector<FarChoiceSample> samples = far_choice_samples(work, config);
  work.far = choose_far_field(
      eyes, work.far_chunks, samples, mode, config.far_geometry_factor,
      [&](std::size_t sample, int face) -> const FaceMesh& {
        return own_time.pause_during([&]() -> const FaceMesh& { return face_mesh(work, config, sample, face); });
      },
      [&](std::size_t sample, int face) {
        return own_time.pause_during([&] { return face_mesh_bound(work, config, sample, face); });
      },
      lods);
}

// The row's far geometry (whole chunks by reference, seen triangles by their
// numbers in the stored chunk: the viewer cuts them out of the store's chunk)
// and its per-face choice.
void write_far_rows(CellWork& work, const ChunkSource& source) {
  CellRow& row = work.row;
  row.far_geometry.clear();
  row.far_choice.clear();
  row.far_geometry_triangles = work.far->geometry_triangles;
  for (const FarPiece& piece : work.far->pieces) {
    FarGeometryRow g;
    g.chunk_id = piece.chunk.id;
    g.triangles = std::uint32_t(piece.triangle_count());
    g.whole = piece.triangles.empty();
    g.level = piece.level;  // a simplified level is drawn whole, from the store
    g.bounds = piece.chunk.bounds;
    if (!g.whole) {
      const Chunk part = chunk_subset(*source.load(piece.chunk.id), piece.triangles);
      g.origin = part.origin;
      g.bounds = part.bounds;
      g.geometry = encode_triangle_list(piece.triangles);
      row.bytes += g.geometry.size();
    }
    row.far_geometry.push_back(std::move(g));
  }
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceFarChoice& c = work.far->faces[std::size_t(f)];
    if (c.geometry_tiles == 0 && c.replaced_triangles == 0 && c.tdm_triangles == 0) continue;
    row.far_choice.push_back({f, c.geometry_tiles, c.tdm_triangles, c.replaced_triangles, c.geometry_triangles});
  }
}

}  // namespace

void run_far_choice(CellWork& work, const BakeConfig& config, const ChunkSource& source) {
  StageTimer own_time(work, "far_choice");  // paused while the stages run inside it time themselves
  grow_seen_rings(work, config, source);
  const Box3d eyes = viewer_eyes(work);
  const std::vector<FarLodChoice> lods = choose_far_levels(work, config, source, eyes);
  choose_far(work, config, eyes, lods, own_time);
  for (const char* stage : {"redundancy", "simplify"}) work.seconds.try_emplace(stage, 0.0);  // 0 when skipped
  for (SampleWork& s : work.samples)  // bounded faces the choice never meshed: drawn wholly as geometry
    for (auto& p : s.pending) p.reset();
  drop_replaced_and_measure_kept(work, config, own_time);
  work.depth_mesh_scratch = DepthMeshScratch{};
  work.far_chunks.clear();
  write_far_rows(work, source);
}


void run_encode(CellWork& work, const BakeConfig& config) {
  StageTimer timer(work, "encode");
  ImageEncodeParams ip;
  ip.format = config.image_format;
  ip.quality = config.image_quality;
  MeshEncodeParams mp;
  mp.position_bits = config.position_bits;
  mp.depth_error_relative = config.mesh_depth_error;
  CellRow& row = work.row;
  row.samples.clear();

  for (std::size_t i = 0; i < work.samples.size(); ++i) {
    SampleWork& s = work.samples[i];
    const auto t0 = Clock::now();
    SampleRow sample;
    sample.index = int(i);
    sample.eye = s.cube.eye;
    sample.parent = s.parent;
    sample.void_after = s.void_after;
    sample.covered_pixels = s.covered;
    sample.removed_pixels = s.removed;
    for (int f = 0; f < kCubeFaces; ++f) {
      CubeFace& face = s.cube.faces[f];
      FaceRow fr;
      fr.face = f;
      fr.image_format = config.image_format;
      if (s.simplified[f].triangle_count() > 0) {
        fill_unread_colors(face, s.simplified[f]);
        fr.image = encode_image(face.color, face.size, face.size, ip);
      } else {
        // Nothing of this face is drawn (sky, or geometry stands in for all
        // of it): no image (encode version 3 stored a 1 x 1 one, ~300 bytes in AVIF).
        fr.image_format = kNoFaceImage;
      }
      if (config.mesh_codec == "grid") mp.face = f, mp.face_size = face.size;
      fr.mesh = encode_face_mesh(s.simplified[f], mp);
      fr.triangles = static_cast<std::uint32_t>(s.simplified[f].triangle_count());
      fr.boundary_error_px = s.boundary_error_px[f];
      fr.depth_error = s.depth_error[f];
      row.far_triangles += fr.triangles;
      row.bytes += fr.image.size() + fr.mesh.size();
      row.max_boundary_error_px = std::max(row.max_boundary_error_px, fr.boundary_error_px);
      row.max_depth_error = std::max(row.max_depth_error, fr.depth_error);
      sample.faces.push_back(std::move(fr));
      face = CubeFace{};
    }
    s.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    sample.seconds = s.seconds;
    row.samples.push_back(std::move(sample));
  }
  work.samples.clear();
}

CellRow finish_cell_row(CellWork& work) {
  CellRow& row = work.row;
  const CellSpec& c = work.cell;
  row.id = c.id;
  row.region = c.region;
  row.gx = c.gx;
  row.gy = c.gy;
  row.gz = c.gz;
  row.bounds = c.bounds;
  row.input_hash = work.hashes.input;
  row.cull_hash = work.hashes.cull;
  row.stage_seconds = work.seconds;
  if (work.cull) {
    row.cull_half_size = work.cull->half_size;
    row.near_triangles = work.cull->triangle_count;
    row.near_chunks.clear();
    for (const auto& n : work.cull->near_field) row.near_chunks.push_back({n.chunk_id, n.triangles, n.whole});
  }
  if (!work.failed_stage.empty()) {
    row.status = "failed";
    row.error = work.error;
    row.samples.clear();
    row.content_hash = "";
    return row;
  }
  row.status = "done";
  row.content_hash = cell_content_hash(row);  // everything a viewer reads, nothing about timing
  return row;
}

}  // namespace cellbake
