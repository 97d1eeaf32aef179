#include "pipeline/cell_job.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <tuple>
#include <utility>

#include "pipeline/cell_job_timer.h"
#include "pipeline/sample_backend.h"
#include "stages/background_fill.h"
#include "stages/encode/encode.h"
#include "stages/hashing.h"
#include "stages/sample/cube_sampler.h"
#include "stages/sample/sample.h"
#include "stages/sample/sample_candidates.h"
#include "stages/sample/sample_points.h"
#include "stages/sample/sample_void.h"
#include "storage/cell_content_hash.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

void hash_vec(Hasher& h, const Vec3d& v) { h.f64(v.x).f64(v.y).f64(v.z); }

void hash_box(Hasher& h, const Box3d& b) {
  h.f64(b.lo.x).f64(b.lo.y).f64(b.lo.z).f64(b.hi.x).f64(b.hi.y).f64(b.hi.z);
}

// Whether the cell's first sample alone finds a far field drawn all as
// geometry (sparse_far_field on a copy of what it saw, grown).
bool first_sample_finds_sparse(CellWork& work, const BakeConfig& config, const ChunkSource& source) {
  CellWork probe;
  probe.chunk_facts = std::move(work.chunk_facts);  // learned for the later growth of every sample
  probe.cell = work.cell;
  probe.far_chunks = work.far_chunks;
  probe.samples.resize(1);
  const CubeSample& first = work.samples.front().cube;
  CubeSample& copy = probe.samples.front().cube;
  copy.eye = first.eye;
  for (int f = 0; f < kCubeFaces; ++f) {
    copy.faces[std::size_t(f)].size = first.faces[std::size_t(f)].size;
    copy.faces[std::size_t(f)].depth = first.faces[std::size_t(f)].depth;
    copy.faces[std::size_t(f)].seen = first.faces[std::size_t(f)].seen;
  }
  grow_seen_rings(probe, config, source, 0, 1);
  const bool sparse = sparse_far_field(probe, config, source).has_value();
  if (sparse) work.chunk_facts = std::move(probe.chunk_facts);  // else freed: run_far_choice grows much later
  return sparse;
}

// After a cell took visibility samples: its seen sets grown, and the far
// field drawn all as geometry kept for run_far_choice; or, when the samples
// together see more than that allows, the small ones taken again at full
// size (their seen sets grown in turn), for the per-tile choice.
void settle_visibility_samples(CellWork& work, const BakeConfig& config, const ChunkSource& source,
                               CubeSampler& sampler, const SampleParams& full, const Box3d& discard_box) {
  grow_seen_rings(work, config, source, 0, work.samples.size());
  work.seen_grown = true;
  work.far = sparse_far_field(work, config, source);
  for (std::size_t i = 0; i < work.samples.size() && !work.far; ++i) {
    SampleWork& s = work.samples[i];
    if (!s.visibility) continue;
    const auto t0 = Clock::now();
    s.cube = sampler.sample(s.cube.eye, discard_box, full, source);
    s.visibility = false;
    s.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    grow_seen_rings(work, config, source, i, i + 1);
  }
  work.chunk_facts.clear();
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
  if (const int v = visibility_face_size(c); v > 0) in.text("visibility_face_size").u64(std::uint64_t(v));
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

int visibility_face_size(const BakeConfig& config) {
  return std::clamp(config.samples_visibility_face_size, 0, config.face_size);
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
  // Once the first sample finds a far field drawn all as geometry, the rest
  // only need to find what else is seen: they are taken without colour (and
  // smaller, with samples.visibility_face_size below sample.face_size).
  SampleParams visibility = p;
  visibility.face_size = visibility_face_size(config);
  visibility.colour = false;  // kept only while the far field stays all geometry: no image is stored
  bool later_visibility = false;
  const auto take = [&](const Vec3d& eye) {
    const auto t0 = Clock::now();
    SampleWork s;
    s.cube = sampler.sample(eye, discard_box, later_visibility ? visibility : p, source);
    s.visibility = later_visibility;
    s.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    work.samples.push_back(std::move(s));
  };
  for (const Vec3d& eye : points) {
    take(eye);
    if (work.samples.size() == 1 && visibility.face_size > 0) later_visibility = first_sample_finds_sparse(work, config, source);
  }
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
  if (later_visibility) settle_visibility_samples(work, config, source, sampler, p, discard_box);
}

void run_sample_tree(CellWork& work, const BakeConfig& /*config: the meshing keys are read on demand*/) {
  StageTimer timer(work, "depth_mesh");
  std::vector<Vec3d> eyes;
  for (const SampleWork& s : work.samples) eyes.push_back(s.cube.eye);
  const std::vector<int> parent = sample_dependency_tree(eyes);
  for (std::size_t i = 0; i < work.samples.size(); ++i) work.samples[i].parent = parent[i];
  work.redundancy_removed = false;
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
