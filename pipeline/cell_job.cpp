#include "pipeline/cell_job.h"

#include <chrono>

#include "stages/depth_mesh.h"
#include "stages/encode.h"
#include "stages/hashing.h"
#include "stages/sample.h"
#include "stages/simplify.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

class StageTimer {
 public:
  StageTimer(CellWork& work, const char* stage) : work_(work), stage_(stage), start_(Clock::now()) {}
  ~StageTimer() { work_.seconds[stage_] += std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  CellWork& work_;
  const char* stage_;
  Clock::time_point start_;
};

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
  in.text("depth_mesh").u64(StageVersions::depth_mesh).f64(c.skin_angle_deg).f64(c.depth_jump);
  in.text("simplify").u64(StageVersions::simplify).f64(c.depth_error_relative).f64(c.boundary_error_px).u64(c.max_face_triangles);
  in.text("encode").u64(StageVersions::encode).text(c.image_format).u64(c.image_quality).u64(c.position_bits);
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

void run_sample(CellWork& work, const BakeConfig& config, const ChunkSource& source, ChunkRenderer& renderer) {
  StageTimer timer(work, "sample");
  SampleParams p;
  p.face_size = config.face_size;
  p.supersample = config.supersample;
  p.near_plane = config.near_plane;
  const Box3d cull_box = Box3d::cube(work.cell.center(), work.cull->half_size);
  work.sample = sample_cube(work.cell.center(), cull_box, p, source, renderer);
}

void run_depth_mesh(CellWork& work, const BakeConfig& config) {
  StageTimer timer(work, "depth_mesh");
  DepthMeshParams p;
  p.skin_angle_degrees = config.skin_angle_deg;
  p.max_relative_depth_jump = config.depth_jump;
  work.dense = build_depth_meshes(*work.sample, p);
}

void run_simplify(CellWork& work, const BakeConfig& config) {
  StageTimer timer(work, "simplify");
  SimplifyParams p;
  p.depth_error_relative = config.depth_error_relative;
  p.boundary_error_px = config.boundary_error_px;
  p.max_triangles = static_cast<std::size_t>(config.max_face_triangles);
  for (int f = 0; f < kCubeFaces; ++f) {
    SimplifyResult r = simplify_face_mesh(work.dense[f], config.face_size, p);
    work.simplified[f] = std::move(r.mesh);
    work.boundary_error_px[f] = r.achieved.max_boundary_error_px;
    work.depth_error[f] = r.achieved.max_depth_error_relative;
    work.dense[f] = FaceMesh{};  // release the dense mesh early
  }
}

void run_encode(CellWork& work, const BakeConfig& config) {
  StageTimer timer(work, "encode");
  ImageEncodeParams ip;
  ip.format = config.image_format;
  ip.quality = config.image_quality;
  MeshEncodeParams mp;
  mp.position_bits = config.position_bits;
  CellRow& row = work.row;
  SampleRow sample;
  sample.index = 0;
  sample.eye = work.sample->eye;
  sample.parent = -1;
  for (int f = 0; f < kCubeFaces; ++f) {
    const CubeFace& face = work.sample->faces[f];
    FaceRow fr;
    fr.face = f;
    fr.image_format = config.image_format;
    fr.image = encode_image(face.color, face.size, face.size, ip);
    fr.mesh = encode_face_mesh(work.simplified[f], mp);
    fr.triangles = static_cast<std::uint32_t>(work.simplified[f].triangle_count());
    fr.boundary_error_px = work.boundary_error_px[f];
    fr.depth_error = work.depth_error[f];
    row.far_triangles += fr.triangles;
    row.bytes += fr.image.size() + fr.mesh.size();
    row.max_boundary_error_px = std::max(row.max_boundary_error_px, fr.boundary_error_px);
    row.max_depth_error = std::max(row.max_depth_error, fr.depth_error);
    sample.faces.push_back(std::move(fr));
  }
  row.samples.clear();
  row.samples.push_back(std::move(sample));
  work.sample.reset();
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
  // Content hash: everything a viewer reads, nothing about timing.
  Hasher h;
  h.u64(row.id).f64(row.cull_half_size).u64(row.near_triangles);
  for (const auto& n : row.near_chunks) h.u64(std::uint64_t(n.chunk_id)).u64(n.triangles).u64(n.whole);
  for (const auto& s : row.samples) {
    h.u64(s.index).f64(s.eye.x).f64(s.eye.y).f64(s.eye.z).u64(std::uint64_t(std::int64_t(s.parent)));
    for (const auto& f : s.faces) {
      h.u64(f.face).text(f.image_format).bytes(f.image.data(), f.image.size()).u64(f.image.size());
      h.bytes(f.mesh.data(), f.mesh.size()).u64(f.mesh.size());
    }
  }
  row.content_hash = h.hex();
  return row;
}

}  // namespace cellbake
