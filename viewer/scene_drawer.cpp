#include "viewer/scene_drawer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "stages/chunk_lod.h"
#include "stages/render/gl_functions.h"
#include "viewer/decoded_cell.h"
#include "viewer/chunk_level_budget.h"
#include "viewer/shared_gl_context.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

// Chunk `id`'s reference in `refs` (sorted by id); null when not there.
const ChunkRef* find_ref(const std::vector<ChunkRef>& refs, std::int64_t id) {
  const auto it =
      std::lower_bound(refs.begin(), refs.end(), id, [](const ChunkRef& r, std::int64_t v) { return r.id < v; });
  return it == refs.end() || it->id != id ? nullptr : &*it;
}

// The ids of `ids` found in `refs` (sorted by id), in their order.
std::vector<std::int64_t> ids_among(const std::vector<std::int64_t>& ids, const std::vector<ChunkRef>& refs) {
  std::vector<std::int64_t> out;
  for (std::int64_t id : ids)
    if (find_ref(refs, id)) out.push_back(id);
  return out;
}

// Level `level` of store chunk `chunk_id`, drawn and cached under `id`.
std::shared_ptr<const Chunk> level_as(const ChunkSource& source, std::int64_t chunk_id, int level, std::int64_t id) {
  auto chunk = std::make_shared<Chunk>(*source.load_lod(chunk_id, level));
  chunk->id = id;
  return chunk;
}

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// A stable, saturated colour per cell id (golden-ratio hue steps).
void cell_tint(std::int64_t id, float tint[4]) {
  const double hue = std::fmod(static_cast<double>(id) * 0.61803398875, 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(hue, 2.0) - 1.0);
  const int sector = static_cast<int>(hue);
  const double rgb[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
  for (int k = 0; k < 3; ++k) tint[k] = static_cast<float>(rgb[sector % 6][k]);
  tint[3] = 0.4f;
}

std::unique_ptr<GlFunctions> load_functions(GlContext& context) {
  context.make_current();
  return std::make_unique<GlFunctions>(load_gl_functions(context));
}

}  // namespace

SceneDrawer::SceneDrawer(std::shared_ptr<GlContext> context, const ChunkSource& source, SceneDrawerParams params)
    : context_(std::move(context)),
      source_(source),
      params_(params),
      chunks_(std::make_unique<SharedGlContext>(context_), ChunkRendererParams{params.chunk_cache_bytes}),
      tdm_(context_),
      gl_(load_functions(*context_)) {
  chunks_.use_materials_of(source_);  // textures and alpha tests of the truth and the near field
}

SceneDrawer::~SceneDrawer() = default;

void SceneDrawer::upload_face(const DecodedCell& cell, std::size_t index, std::vector<std::uint64_t>& handles,
                              std::size_t& bytes) {
  const DecodedFace& f = cell.faces[index];
  const std::size_t before = tdm_.gpu_bytes();
  handles.push_back(tdm_.upload(f.mesh, f.image, f.eye));
  bytes += tdm_.gpu_bytes() - before;
}

void SceneDrawer::make_resident(std::int64_t cell_id, ResidentCell resident) {
  lru_.push_front(cell_id);
  resident.recency = lru_.begin();
  resident_bytes_ += resident.bytes;
  cells_.emplace(cell_id, std::move(resident));
  while (resident_bytes_ > params_.tdm_cache_bytes && lru_.size() > 1) {
    const std::int64_t victim = lru_.back();
    lru_.pop_back();
    auto it = cells_.find(victim);
    for (std::uint64_t h : it->second.handles) tdm_.erase(h);
    resident_bytes_ -= it->second.bytes;
    cells_.erase(it);
  }
}

void SceneDrawer::prepare(const DecodedCell& cell) {
  if (auto it = cells_.find(cell.id); it != cells_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.recency);
    return;
  }
  // Faces a part upload (upload_some) already made are kept.
  ResidentCell resident;
  for (auto it = partial_.begin(); it != partial_.end(); ++it)
    if (it->first == cell.id) {
      resident.handles = std::move(it->second.handles);
      resident.bytes = it->second.bytes;
      partial_.erase(it);
      break;
    }
  try {
    for (std::size_t k = resident.handles.size(); k < cell.faces.size(); ++k)
      upload_face(cell, k, resident.handles, resident.bytes);
  } catch (...) {
    for (std::uint64_t h : resident.handles) tdm_.erase(h);
    throw;
  }
  make_resident(cell.id, std::move(resident));
}

UploadProgress SceneDrawer::upload_some(const DecodedCell& cell, const UploadBudget& budget) {
  const double start = now_ms();
  UploadProgress progress;
  auto part = partial_.begin();
  while (part != partial_.end() && part->first != cell.id) ++part;
  if (part == partial_.end()) {
    partial_.emplace_front(cell.id, PartialCell{});
    // Resident faces (drawn before) are not uploaded again: start at the chunks.
    if (cells_.contains(cell.id)) partial_.front().second.next_item = cell.faces.size();
    PartialCell& fresh = partial_.front().second;
    fresh.coarser = coarser_levels_ahead(cell);
    for (const auto& entry : fresh.coarser) fresh.coarser_ids.push_back(entry.first);
    std::sort(fresh.coarser_ids.begin(), fresh.coarser_ids.end());
    while (partial_.size() > 4) {
      for (std::uint64_t h : partial_.back().second.handles) tdm_.erase(h);
      partial_.pop_back();
    }
  } else {
    partial_.splice(partial_.begin(), partial_, part);
  }
  PartialCell& p = partial_.front().second;
  const std::size_t faces = cell.faces.size(), near = cell.near_ids.size(), pieces = cell.far_pieces.size();
  const std::size_t whole = cell.far_whole_ids.size(), own = faces + near + pieces + whole;
  const std::size_t items = own + p.coarser_ids.size();
  const ChunkLoader load = [this](std::int64_t id) { return source_.load(id); };
  try {
    while (p.next_item < items) {
      if (progress.items > 0 &&
          (progress.bytes >= budget.bytes || now_ms() - start >= budget.milliseconds))
        break;
      const std::size_t k = p.next_item;
      std::size_t bytes = 0;
      if (k < faces) {
        if (!cells_.contains(cell.id)) upload_face(cell, k, p.handles, bytes);
      } else if (k < faces + near) {
        bytes = chunks_.upload_ahead(cell.near_ids[k - faces], load);
      } else if (k < faces + near + pieces) {
        const DecodedFarPiece& piece = cell.far_pieces[k - faces - near];
        bytes = chunks_.upload_ahead(piece.cache_id, [&](std::int64_t) { return far_piece_chunk(piece, source_); });
      } else if (k < own) {
        bytes = chunks_.upload_ahead(cell.far_whole_ids[k - faces - near - pieces], load);
      } else {
        const std::int64_t id = p.coarser_ids[k - own];
        const auto [chunk_id, level] = p.coarser.at(id);
        bytes = chunks_.upload_ahead(
            id, [&, chunk_id = chunk_id, level = level](std::int64_t) { return level_as(source_, chunk_id, level, id); });
      }
      if (k < faces) p.bytes += bytes;
      ++p.next_item;
      if (p.next_item == faces && !cells_.contains(cell.id)) {
        ResidentCell resident;
        resident.handles = std::move(p.handles);
        resident.bytes = p.bytes;
        p.handles.clear();
        p.bytes = 0;
        make_resident(cell.id, std::move(resident));
      }
      if (bytes > 0) {
        progress.bytes += bytes;
        ++progress.items;
      }
    }
  } catch (...) {
    for (std::uint64_t h : p.handles) tdm_.erase(h);
    partial_.pop_front();
    throw;
  }
  progress.complete = p.next_item >= items;
  if (progress.complete) {
    if (faces == 0 && !cells_.contains(cell.id)) make_resident(cell.id, ResidentCell{});
    partial_.pop_front();
  }
  progress.milliseconds = now_ms() - start;
  return progress;
}

void SceneDrawer::set_wireframe(bool on) {
  context_->make_current();
  gl_->PolygonMode(GL_FRONT_AND_BACK, on ? GL_LINE : GL_FILL);
}

SceneFrameStats SceneDrawer::finish(SceneFrameStats stats, const ChunkRendererStats& before, double start_ms,
                                    int width, int height, ViewFrame& out) {
  out.width = width;
  out.height = height;
  chunks_.read_frame(out.color, out.depth);
  const ChunkRendererStats after = chunks_.stats();
  stats.chunk_triangles = after.triangles_drawn - before.triangles_drawn;
  stats.chunks_drawn = after.chunks_drawn - before.chunks_drawn;
  stats.milliseconds = now_ms() - start_ms;
  return stats;
}

SceneFrameStats SceneDrawer::draw_impostor(const RenderCamera& camera, int width, int height, const DecodedCell& cell,
                                           const SceneDrawOptions& options, ViewFrame& out) {
  const double start = now_ms();
  const ChunkRendererStats before = chunks_.stats();
  if (options.far_field) prepare(cell);
  const double prepared = now_ms();
  chunks_.begin_frame(width, height);
  set_wireframe(options.wireframe);
  SceneFrameStats stats;
  try {
    // The near field whole: a near field clipped at the box would leave a
    // band wherever the eye is not at a sample point; the overlap with the
    // far field (which also reaches a shell inside the box) is resolved by
    // the depth test.
    // What the cell draws of the store's chunks in view: its near field, and
    // its exact far geometry (pieces of chunks, whole chunks), frustum-culled
    // like the truth.
    const bool far_geometry = options.far_field && (!cell.far_pieces.empty() || !cell.far_whole_ids.empty());
    CellChunksInView drawn = cell_chunks_in_view(camera, cell, options.near_field, far_geometry);
    last_camera_ = camera, last_height_ = height, last_max_chunk_triangles_ = options.max_chunk_triangles;
    // Over the frame's budget: coarser store levels, drawn under their own cache ids.
    const CoarserLevels coarser = options.max_chunk_triangles > 0
                                      ? coarser_levels(camera, height, cell, options.max_chunk_triangles, drawn)
                                      : CoarserLevels{};
    const auto load_coarser = [&](std::int64_t id) -> std::shared_ptr<const Chunk> {
      const auto it = coarser.find(id);
      return it == coarser.end() ? nullptr : level_as(source_, it->second.first, it->second.second, id);
    };
    const ChunkLoader load_chunk = [&](std::int64_t id) {
      if (auto level = load_coarser(id)) return level;
      return source_.load(id);
    };
    if (!drawn.near.empty()) chunks_.draw(camera, Box3d{}, drawn.near, load_chunk);
    if (far_geometry) {
      const std::uint64_t drawn_before = chunks_.stats().triangles_drawn;
      const ChunkLoader load_piece = [&](std::int64_t cache_id) {
        if (auto level = load_coarser(cache_id)) return level;
        const auto it = std::find_if(cell.far_pieces.begin(), cell.far_pieces.end(),
                                     [cache_id](const DecodedFarPiece& p) { return p.cache_id == cache_id; });
        // Cells decoded without a source: cut out of the store's chunk, or the
        // store's level loaded (shared by every cell drawing it: one cache id).
        return far_piece_chunk(*it, source_);
      };
      chunks_.draw(camera, Box3d{}, drawn.pieces, load_piece);
      if (!drawn.whole.empty()) chunks_.draw(camera, Box3d{}, drawn.whole, load_chunk);
      stats.far_geometry_triangles = chunks_.stats().triangles_drawn - drawn_before;
    }
    if (options.far_field) {
      TdmDrawOptions tdm_options;
      tdm_options.wireframe = options.wireframe;
      if (options.tint_by_cell) cell_tint(cell.id, tdm_options.tint);
      // The budget counts what this view would draw: each sample's face tiles in the frustum.
      struct VisibleTile {
        std::size_t face;  // index into cell.faces (and its upload handle)
        std::uint32_t first_index, index_count;
      };
      std::vector<VisibleTile> visible;
      std::vector<SampleNode> nodes = cell.samples;
      for (SampleNode& n : nodes) n.triangles = 0;
      for (std::size_t k = 0; k < cell.faces.size(); ++k) {
        const DecodedFace& f = cell.faces[k];
        if (!box_in_view(camera, f.bounds)) continue;
        for (const FaceTile& t : f.tiles) {
          if (!box_in_view(camera, t.bounds)) continue;
          visible.push_back({k, t.first_index, t.index_count});
          for (SampleNode& n : nodes)
            if (n.index == f.sample) n.triangles += t.index_count / 3;
        }
      }
      const std::vector<int> chosen = select_samples(nodes, camera.eye, options.samples);
      const std::vector<std::uint64_t>& all = cells_.at(cell.id).handles;
      std::vector<TdmRenderer::Range> ranges;
      for (const VisibleTile& t : visible)
        if (t.face < all.size() && std::find(chosen.begin(), chosen.end(), cell.faces[t.face].sample) != chosen.end())
          ranges.push_back({all[t.face], t.first_index, t.index_count});
      stats.samples_drawn = chosen.size();
      stats.far_triangles = tdm_.draw_ranges(camera, chunks_.reversed_z(), ranges, tdm_options);
    }
  } catch (...) {
    set_wireframe(false);
    throw;
  }
  set_wireframe(false);
  stats.prepare_milliseconds = prepared - start;
  return finish(stats, before, start, width, height, out);
}

SceneDrawer::CellChunksInView SceneDrawer::cell_chunks_in_view(const RenderCamera& camera, const DecodedCell& cell,
                                                               bool near_field, bool far_geometry) const {
  CellChunksInView v;
  if (near_field || (far_geometry && !cell.far_whole_ids.empty())) v.refs = chunk_refs_in_view(camera, source_);
  if (near_field) v.near = ids_among(cell.near_ids, v.refs);
  if (far_geometry) {
    for (const DecodedFarPiece& p : cell.far_pieces)
      if (box_in_view(camera, p.bounds)) v.pieces.push_back(p.cache_id);
    v.whole = ids_among(cell.far_whole_ids, v.refs);
  }
  return v;
}

SceneDrawer::CoarserLevels SceneDrawer::coarser_levels(const RenderCamera& camera, int height,
                                                      const DecodedCell& cell, std::uint64_t max_triangles,
                                                      CellChunksInView& drawn) const {
  std::vector<ChunkDrawItem> items;
  std::vector<std::int64_t*> ids;  // the list entry each item's id is in
  const auto add_chunks = [&](std::vector<std::int64_t>& list) {
    for (std::int64_t& id : list)
      if (const ChunkRef* r = find_ref(drawn.refs, id)) {
        items.push_back({id, 0, r->triangle_count, r->bounds});
        ids.push_back(&id);
      }
  };
  add_chunks(drawn.near);
  // The cell's pieces by cache id (pieces lists some of them, in the cell's order).
  std::size_t next = 0;
  for (std::int64_t& id : drawn.pieces) {
    while (next < cell.far_pieces.size() && cell.far_pieces[next].cache_id != id) ++next;
    if (next == cell.far_pieces.size()) throw std::logic_error("coarser_levels: a piece not of the cell, or out of order");
    const DecodedFarPiece& p = cell.far_pieces[next];
    items.push_back({p.chunk_id, p.level, far_piece_triangles(p, source_), p.bounds});
    ids.push_back(&id);
  }
  add_chunks(drawn.whole);
  const double per_distance = (camera.tan_top - camera.tan_bottom) / double(std::max(height, 1));
  const std::vector<int> levels = levels_for_triangle_budget(items, source_, camera.eye, per_distance, max_triangles);
  CoarserLevels coarser;
  for (std::size_t i = 0; i < items.size(); ++i)
    if (levels[i] != items[i].level) {
      *ids[i] = lod_cache_id(items[i].chunk_id, levels[i]);
      coarser.emplace(*ids[i], std::make_pair(items[i].chunk_id, levels[i]));
    }
  return coarser;
}

SceneDrawer::CoarserLevels SceneDrawer::coarser_levels_ahead(const DecodedCell& cell) const {
  if (last_max_chunk_triangles_ == 0) return {};
  CellChunksInView drawn = cell_chunks_in_view(last_camera_, cell, true, true);
  return coarser_levels(last_camera_, last_height_, cell, last_max_chunk_triangles_, drawn);
}

SceneFrameStats SceneDrawer::draw_truth(const RenderCamera& camera, int width, int height,
                                        const SceneDrawOptions& options, ViewFrame& out) {
  const double start = now_ms();
  const ChunkRendererStats before = chunks_.stats();
  const ChunkLoader load = [this](std::int64_t id) { return source_.load(id); };
  chunks_.begin_frame(width, height);
  set_wireframe(options.wireframe);
  try {
    if (options.truth_occlusion_culling && !options.wireframe) {
      std::vector<ChunkRef> refs = chunk_refs_in_view(camera, source_);  // sorted by id: ties keep id order
      std::stable_sort(refs.begin(), refs.end(), [&camera](const ChunkRef& a, const ChunkRef& b) {
        return a.bounds.distance_to(camera.eye) < b.bounds.distance_to(camera.eye);
      });
      chunks_.draw_unoccluded(camera, Box3d{}, refs, load);
    } else {
      chunks_.draw(camera, Box3d{}, chunks_in_view(camera, source_), load);
    }
  } catch (...) {
    set_wireframe(false);
    throw;
  }
  set_wireframe(false);
  return finish({}, before, start, width, height, out);
}

SceneFrameStats SceneDrawer::draw_lod_cut(const RenderCamera& camera, int width, int height,
                                          const SceneDrawOptions& options, std::uint64_t max_triangles,
                                          double error_px, ViewFrame& out, LodCut* cut_out) {
  const double start = now_ms();
  const ChunkRendererStats before = chunks_.stats();
  const std::vector<ChunkRef> refs = chunk_refs_in_view(camera, source_);
  // Metres per pixel at a chunk's nearest point: the view's height spans
  // distance * (tan_top - tan_bottom) there.
  const double per_distance = (camera.tan_top - camera.tan_bottom) / double(height);
  std::vector<LodCutChunk> chunks;
  chunks.reserve(refs.size());
  for (const ChunkRef& r : refs) {
    const double distance = box_distance(Box3d{camera.eye, camera.eye}, r.bounds);
    chunks.push_back({distance * per_distance, std::uint32_t(r.triangle_count), source_.lods(r.id)});
  }
  LodCut cut = max_triangles > 0 ? lod_cut_for_triangles(chunks, max_triangles) : lod_cut_at_error(chunks, error_px);
  std::vector<std::int64_t> ids;
  std::unordered_map<std::int64_t, std::pair<std::int64_t, int>> level_of_id;
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const int level = cut.levels[i];
    const std::int64_t id = level > 0 ? lod_cache_id(refs[i].id, level) : refs[i].id;
    ids.push_back(id);
    if (level > 0) level_of_id.emplace(id, std::make_pair(refs[i].id, level));
  }
  chunks_.begin_frame(width, height);
  set_wireframe(options.wireframe);
  try {
    chunks_.draw(camera, Box3d{}, ids, [&](std::int64_t id) {
      const auto it = level_of_id.find(id);
      if (it == level_of_id.end()) return source_.load(id);
      return level_as(source_, it->second.first, it->second.second, id);  // cached under its level's id
    });
  } catch (...) {
    set_wireframe(false);
    throw;
  }
  set_wireframe(false);
  if (cut_out) *cut_out = std::move(cut);
  return finish({}, before, start, width, height, out);
}

}  // namespace cellbake
