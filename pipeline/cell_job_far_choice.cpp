// The far choice step of the per-cell job (pipeline/cell_job.h
// run_far_choice), its named steps in the order they run: seen triangles
// grown, far chunk levels chosen, the choice (stages/far/far_choice.h)
// meshing faces on demand, the replaced triangles dropped and the kept
// meshes measured, the row's far geometry written.
#include <algorithm>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

#include "pipeline/cell_job.h"
#include "pipeline/cell_job_timer.h"
#include "stages/chunk_lod.h"
#include "stages/chunk_subset.h"
#include "stages/depth_mesh.h"
#include "stages/encode/encode_triangle_list.h"
#include "stages/far/far_choice.h"
#include "stages/simplify/simplify.h"

namespace cellbake {
namespace {

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

}  // namespace

double ChunkWidths::of(std::int64_t id, const ChunkSource& source) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (const auto it = widths_.find(id); it != widths_.end()) return it->second;
  }
  // Computed outside the lock: two threads may both compute it, to the same value.
  const double width = median_triangle_width(*source.load(id));
  const std::lock_guard<std::mutex> lock(mutex_);
  return widths_.try_emplace(id, width).first->second;
}

void grow_seen_rings(CellWork& work, const BakeConfig& config, const ChunkSource& source, std::size_t first,
                     std::size_t last) {
  if (config.far_seen_rings <= 0) return;
  std::vector<std::uint16_t> scratch;
  for (std::size_t i = first; i < std::min(last, work.samples.size()); ++i)
    for (CubeFace& face : work.samples[i].cube.faces)
      for (SeenChunk& seen : face.seen) {
        if (seen.whole()) continue;
        CellWork::ChunkFacts& facts = work.chunk_facts[seen.id];
        if (!facts.chunk) {
          facts.chunk = source.load(seen.id);
          facts.adjacency = vertex_triangles(*facts.chunk);
        }
        grow_seen_triangles(seen, *facts.chunk, facts.adjacency, config.far_seen_rings, scratch);
      }
}

namespace {

// median_triangle_width of chunk `id`: the bake's, learned once (work.widths), or computed.
double median_width(const CellWork& work, const ChunkSource& source, std::int64_t id) {
  return work.widths ? work.widths->of(id, source) : median_triangle_width(*source.load(id));
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
          seen[i] && seen_subset_may_miss(median_width(work, source, work.far_chunks[i].id), distance,
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
  double hits = 0;  // pixels of the samples that saw a far surface, at sample.face_size
  for (const SampleWork& s : work.samples)
    for (const CubeFace& face : s.cube.faces) {
      std::uint64_t n = 0;
      for (const float d : face.depth) n += d < kBackgroundDepth;
      const double scale = face.size > 0 ? double(config.face_size) / double(face.size) : 1.0;
      hits += double(n) * scale * scale;
    }
  if (double(all.geometry_triangles) > config.far_seen_geometry_per_hit * hits) return std::nullopt;
  return all;
}

// The samples as the far choice reads them: the faces meshed so far, what
// each face saw, and for the others a guess of their mesh's size.
std::vector<FarChoiceSample> far_choice_samples(const CellWork& work, const BakeConfig& config) {
  const DepthMeshParams mesh_params = cell_depth_mesh_params(config);
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
  for (const SampleWork& s : work.samples)
    if (s.visibility) throw std::logic_error("far choice: a visibility sample reached the per-tile choice");
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

std::optional<FarChoice> sparse_far_field(const CellWork& work, const BakeConfig& config, const ChunkSource& source) {
  if (parse_far_choice_mode(config.far_choice) != FarChoiceMode::cheapest) return std::nullopt;
  const Box3d eyes = viewer_eyes(work);
  return sparse_seen_far_field(work, config, eyes, choose_far_levels(work, config, source, eyes));
}

void run_far_choice(CellWork& work, const BakeConfig& config, const ChunkSource& source) {
  StageTimer own_time(work, "far_choice");  // paused while the stages run inside it time themselves
  if (!work.seen_grown) grow_seen_rings(work, config, source, 0, work.samples.size());
  work.seen_grown = true;
  work.chunk_facts.clear();  // the chunks' memory back before meshing
  if (!work.far) {  // run_sample may have found it already (visibility samples)
    const Box3d eyes = viewer_eyes(work);
    const std::vector<FarLodChoice> lods = choose_far_levels(work, config, source, eyes);
    choose_far(work, config, eyes, lods, own_time);
  }
  for (const char* stage : {"redundancy", "simplify"}) work.seconds.try_emplace(stage, 0.0);  // 0 when skipped
  for (SampleWork& s : work.samples)  // bounded faces the choice never meshed: drawn wholly as geometry
    for (auto& p : s.pending) p.reset();
  drop_replaced_and_measure_kept(work, config, own_time);
  work.depth_mesh_scratch = DepthMeshScratch{};
  work.far_chunks.clear();
  write_far_rows(work, source);
}

}  // namespace cellbake
