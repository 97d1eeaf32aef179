// The stages run_far_choice runs on demand (pipeline/cell_job.h): the delta
// scans' redundant pixels removed, a face's depth mesh built and simplified
// (or bounded first), and the simplifier's error measured for the faces kept.
#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/cell_job.h"
#include "pipeline/cell_job_timer.h"
#include "stages/depth_mesh.h"
#include "stages/sample/sample_points.h"
#include "stages/sample/sample_redundancy.h"
#include "stages/simplify/simplify.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

// The parameters for meshing sample `i` of `work`: every other sample that
// kept its depths as taken is a skin witness.
DepthMeshParams depth_mesh_params(const BakeConfig& config, const CellWork& work, std::size_t i) {
  DepthMeshParams p = cell_depth_mesh_params(config);
  for (std::size_t k = 0; k < work.samples.size(); ++k)
    if (k != i && !work.samples[k].taken_depth[0].empty())
      p.witnesses.push_back({work.samples[k].cube.eye, &work.samples[k].taken_depth, work.samples[k].cube.faces[0].size});
  return p;
}

}  // namespace

DepthMeshParams cell_depth_mesh_params(const BakeConfig& config) {
  DepthMeshParams p;
  p.skin_angle_degrees = config.skin_angle_deg;
  p.max_relative_depth_jump = config.depth_jump;
  return p;
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

}  // namespace cellbake
