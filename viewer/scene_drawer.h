// The drawing shared by `cellbake render` and the interactive viewer: a view
// cell's impostor (near field = its chunk list drawn whole, so that triangles
// crossing the cull box reach past it and meet the far field without a seam
// from anywhere in the cell (Wilson 2002, Fig. 1.6); plus the textured depth
// meshes of the samples chosen for the eye; depth-tested together; ch. 2, 5
// and 7) and the ground truth (every chunk in the view frustum, nothing
// discarded), on one GL context.
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <unordered_map>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/far/lod_cut.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "viewer/decoded_cell.h"
#include "viewer/image_metrics.h"
#include "viewer/tdm_renderer.h"

namespace cellbake {

struct GlFunctions;

struct SceneDrawerParams {
  std::size_t chunk_cache_bytes = std::size_t{512} << 20;  // GPU chunk buffers (ChunkRenderer's LRU cap)
  std::size_t tdm_cache_bytes = std::size_t{512} << 20;    // GPU textured depth meshes, LRU by cell
};

struct SceneDrawOptions {
  bool near_field = true;
  bool far_field = true;
  bool wireframe = false;
  bool tint_by_cell = false;  // mix a colour derived from the cell id into its far field
  // Which samples' textured depth meshes to draw (viewer/sample_selection.h):
  // the nearest sample to the camera with its ancestors, then more while the
  // far-field triangle budget allows; max_samples = 1 draws the root alone.
  SampleSelectionParams samples;
  // draw_truth: chunks drawn nearest first, skipping those provably hidden
  // behind what is already drawn (ChunkRenderer::draw_unoccluded): the same
  // image except where two surfaces tie exactly in depth, at a fraction of
  // the drawing where walls hide most of the model. Ignored in wireframe.
  bool truth_occlusion_culling = false;
  // draw_impostor: at most this many triangles of the store's chunks in view
  // (near field and exact far geometry), drawing them at coarser store levels
  // where needed, least projected error first (viewer/chunk_level_budget.h);
  // 0: as the cell stored them.
  std::uint64_t max_chunk_triangles = 0;
};

// A frame's allowance for GPU uploads ahead of drawing (SceneDrawer::upload_some).
struct UploadBudget {
  std::size_t bytes = std::size_t{8} << 20;  // vertex, index and texture bytes
  double milliseconds = 6;                   // wall clock spent loading and uploading
};

struct UploadProgress {
  std::size_t bytes = 0;    // uploaded by this call
  std::size_t items = 0;    // faces and chunks uploaded by this call
  double milliseconds = 0;  // spent in this call
  bool complete = false;    // every face and chunk of the cell has been uploaded (or found cached)
};

struct SceneFrameStats {
  std::uint64_t chunk_triangles = 0;  // chunk triangles submitted (whole chunks, before discard)
  std::uint64_t far_triangles = 0;    // textured depth mesh triangles submitted
  std::uint64_t far_geometry_triangles = 0;  // exact far geometry triangles submitted (also in chunk_triangles)
  std::uint64_t samples_drawn = 0;    // samples whose faces were considered (before per-face culling)
  std::uint64_t chunks_drawn = 0;
  double milliseconds = 0;  // begin_frame to read-back, wall clock
  double prepare_milliseconds = 0;  // of those, uploading the cell's faces not yet resident
};

class SceneDrawer {
 public:
  // Draws `source` (which must outlive the drawer) with `context` (shared with
  // nothing else). Throws std::runtime_error when the context cannot draw.
  SceneDrawer(std::shared_ptr<GlContext> context, const ChunkSource& source, SceneDrawerParams params = {});
  ~SceneDrawer();

  // Uploads the cell's faces unless already resident; evicts least recently
  // used cells beyond the cap (never `cell`).
  void prepare(const DecodedCell& cell);
  bool is_prepared(std::int64_t cell_id) const { return cells_.contains(cell_id); }
  // Uploads part of what drawing `cell` needs: its faces (textured depth
  // meshes), then its near-field chunks, far pieces and whole far chunks, in
  // that order, resuming where the previous call for the cell stopped, and
  // stops before the next face or chunk once `budget` bytes or milliseconds
  // are spent (the first one always goes, so every call makes progress).
  // Chunks already cached cost nothing. When the last impostor frame drew
  // under a chunk budget, the coarser levels the cell's chunks in view would
  // draw from that frame's camera under it come last (a switch then finds the
  // levels it draws uploaded). Once its faces are uploaded the cell
  // is prepared (prepare()'s eviction applies). `complete` when nothing is
  // left; later calls for the cell start over (finding everything cached).
  // Up to four cells are kept part-uploaded; a fifth frees the oldest's faces.
  // Never draws. Throws as prepare() and ChunkRenderer::upload_ahead do.
  UploadProgress upload_some(const DecodedCell& cell, const UploadBudget& budget);

  // Renders the impostor of `cell` (prepared on demand) into a width x height
  // frame and reads it back into `out` (colour + planar depth).
  SceneFrameStats draw_impostor(const RenderCamera& camera, int width, int height, const DecodedCell& cell,
                                const SceneDrawOptions& options, ViewFrame& out);
  // Renders every chunk in the camera's frustum, nothing discarded.
  SceneFrameStats draw_truth(const RenderCamera& camera, int width, int height, const SceneDrawOptions& options,
                             ViewFrame& out);

  // Renders every chunk in the camera's frustum at the store's levels
  // (stages/far/lod_cut.h): at `error_px` pixels when max_triangles is 0, else at
  // the finest cut of at most `max_triangles` triangles. The cut made is
  // returned through `cut` when given (levels in chunk id order).
  SceneFrameStats draw_lod_cut(const RenderCamera& camera, int width, int height, const SceneDrawOptions& options,
                               std::uint64_t max_triangles, double error_px, ViewFrame& out, LodCut* cut = nullptr);

  // The light model of the chunks drawn from now on (near field and truth;
  // ChunkRenderer::set_shading). Viewers pass the bake's own
  // (shading_of_config_text of the database's meta `config`), so that truth
  // and near field are lit like the far field's baked images.
  void set_shading(const ShadingLights& lights) { chunks_.set_shading(lights); }

  std::size_t tdm_gpu_bytes() const { return tdm_.gpu_bytes(); }
  // True when the resident faces and the cached chunks each fill at most
  // `fraction` of their caps (SceneDrawerParams): room to upload ahead.
  bool gpu_caches_below(double fraction) const {
    return resident_bytes_ <= fraction * params_.tdm_cache_bytes &&
           chunks_.stats().cached_bytes <= fraction * params_.chunk_cache_bytes;
  }
  // Bytes uploaded so far: faces (textured depth meshes) and chunks.
  std::uint64_t uploaded_bytes() const { return tdm_.uploaded_bytes() + chunks_.stats().uploaded_bytes; }
  ChunkRendererStats chunk_stats() const { return chunks_.stats(); }
  // Leaves the calling thread without a current context.
  void release_context() { context_->release_current(); }

 private:
  struct ResidentCell {
    std::vector<std::uint64_t> handles;
    std::size_t bytes = 0;
    std::list<std::int64_t>::iterator recency;
  };
  // Chunk id -> (store chunk, level) of what a frame draws at a coarser level.
  using CoarserLevels = std::unordered_map<std::int64_t, std::pair<std::int64_t, int>>;
  // What draw_impostor draws of the store's chunks from `camera`: the chunks
  // in view (by id), and of the cell's, the near chunks (with `near_field`),
  // far pieces (cache ids, in the cell's order) and whole far chunks (with
  // `far_geometry`) in view.
  struct CellChunksInView {
    std::vector<ChunkRef> refs;
    std::vector<std::int64_t> near, pieces, whole;
  };
  CellChunksInView cell_chunks_in_view(const RenderCamera& camera, const DecodedCell& cell, bool near_field,
                                       bool far_geometry) const;
  // draw_impostor over `max_triangles`: the ids in `drawn` that draw a
  // coarser store level (viewer/chunk_level_budget.h) are replaced by
  // lod_cache_id, mapped here to what they draw.
  CoarserLevels coarser_levels(const RenderCamera& camera, int height, const DecodedCell& cell,
                               std::uint64_t max_triangles, CellChunksInView& drawn) const;
  // A cell upload_some() has begun: its faces uploaded so far and the next item
  // (faces first, then near chunks, far pieces, whole far chunks).
  struct PartialCell {
    std::vector<std::uint64_t> handles;
    std::size_t bytes = 0;
    std::size_t next_item = 0;
    // Past the cell's own items: the coarser levels its chunks in view would
    // draw from the last frame's camera under its budget (coarser_levels).
    std::vector<std::int64_t> coarser_ids;
    CoarserLevels coarser;
  };
  // The coarser levels `cell` would draw from the last impostor frame's camera
  // under its chunk budget (none when that frame had no budget).
  CoarserLevels coarser_levels_ahead(const DecodedCell& cell) const;
  // Makes `resident` (all of `cell_id`'s faces) resident as the most recent cell, evicting beyond the cap.
  void make_resident(std::int64_t cell_id, ResidentCell resident);
  // Uploads face `index` of `cell`, appending its handle and adding its bytes.
  void upload_face(const DecodedCell& cell, std::size_t index, std::vector<std::uint64_t>& handles, std::size_t& bytes);
  void set_wireframe(bool on);
  SceneFrameStats finish(SceneFrameStats stats, const ChunkRendererStats& before, double start_ms, int width,
                         int height, ViewFrame& out);

  std::shared_ptr<GlContext> context_;
  const ChunkSource& source_;
  SceneDrawerParams params_;
  ChunkRenderer chunks_;
  TdmRenderer tdm_;
  std::unique_ptr<GlFunctions> gl_;
  std::unordered_map<std::int64_t, ResidentCell> cells_;
  std::list<std::int64_t> lru_;
  std::size_t resident_bytes_ = 0;
  std::list<std::pair<std::int64_t, PartialCell>> partial_;  // front = most recently continued
  // The last draw_impostor's camera, height and chunk budget (0: none).
  RenderCamera last_camera_{};
  int last_height_ = 0;
  std::uint64_t last_max_chunk_triangles_ = 0;
};

}  // namespace cellbake
