// Draws chunked geometry offscreen and reads back colour plus linear planar
// view depth: the drawing core shared by the panoramic sampler (stages/sample/sample.h)
// and the headless viewer.
//
// Precision: chunks keep float32 positions relative to a double origin; every
// draw translates by (chunk.origin - eye) computed in double and cast to float,
// so the GPU only ever sees eye-relative coordinates and models 1e6 m from the
// world origin lose nothing. Depth: the z-test uses reversed-Z with a float
// depth buffer (glClipControl, GL 4.5 / ARB_clip_control) and an infinite far
// plane, or standard [-1, 1] depth with an infinite far plane where clip
// control is missing; what is read back is the exact planar view depth written
// by the fragment shader into an R32F attachment, independent of that choice.
// A discard box removes every fragment whose world position lies strictly
// inside it (the far field of a view cell is everything outside its cull box);
// with BoxClip::keep_inside it keeps exactly those instead (the near field).
// Colours: the chunk's vertex colours, times the texel of the triangle's
// material texture when it has one (trilinear mipmapping, the file's wrap
// modes; alpha-tested materials drop texels with alpha < 0.5), under the fixed
// light model of stages/shading.h (the chunk's vertex normals when it
// has them, else flat face normals from screen-space derivatives), or as they
// are when the shading is unlit.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/cube_map.h"
#include "stages/geometry.h"
#include "stages/render/gl_context.h"
#include "stages/shading.h"

namespace cellbake {

struct GlFunctions;  // stages/render/gl_functions.h; kept out of this header so users need no GL headers
class GlTextureCache;  // stages/render/gl_texture_cache.h
using TextureLoader = std::function<std::shared_ptr<const TextureImage>(std::int64_t id)>;

// A pinhole camera. The basis must be orthonormal and right-handed like an
// OpenGL camera (right x up = -forward); the image's x axis runs along
// `right`, its y axis along `up`. The frustum is given by the tangents of its
// edges at unit forward distance (a 90-degree cube face: -1, 1, -1, 1).
struct RenderCamera {
  Vec3d eye;  // world coordinates
  Vec3d forward{0, 0, -1};
  Vec3d right{1, 0, 0};
  Vec3d up{0, 1, 0};
  double tan_left = -1, tan_right = 1, tan_bottom = -1, tan_top = 1;
  double near_plane = 0.01;  // metres along forward; nearer geometry is clipped
};

// The camera of cube face `face` (0..5, stages/cube_map.h) at `eye`: the
// face's basis and its 90-degree frustum.
inline RenderCamera cube_face_camera(const Vec3d& eye, int face, double near_plane = 0.01) {
  const FaceBasis b = cube_face_basis(face);
  RenderCamera camera;
  camera.eye = eye;
  camera.forward = b.forward;
  camera.right = b.right;
  camera.up = b.up;
  camera.near_plane = near_plane;
  return camera;
}

// What draw() does with fragments relative to its box. The two modes are exact
// complements: a fragment on the box boundary is kept by discard_inside only.
enum class BoxClip {
  discard_inside,  // drop fragments strictly inside the box (the sampler's far field)
  keep_inside,     // keep only fragments strictly inside the box (a viewer's near field); an empty box keeps nothing
};

// The column-major 4x4 matrix (projection * rotation into the camera frame)
// that ChunkRenderer applies to eye-relative world positions: off-axis
// perspective with an infinite far plane, reversed-Z ([0, 1], 1 at the near
// plane) when `reversed_z`, else standard [-1, 1]. Other drawers that share a
// renderer's frame (the viewer's textured depth meshes) use it to match its
// depth test exactly.
std::array<float, 16> camera_view_projection(const RenderCamera& camera, bool reversed_z);

struct ChunkRendererParams {
  // Cap on the bytes of cached chunk buffers (vertex + index data); the least
  // recently drawn chunks are evicted beyond it. A single chunk larger than the
  // cap is still drawn (it is then the only one cached).
  std::size_t cache_bytes = std::size_t{1} << 30;
  // Cap on the GL memory of cached textures (mip chains included).
  std::size_t texture_cache_bytes = std::size_t{512} << 20;
};

// A run of a cached chunk's indices that share one material.
struct ChunkDrawRange {
  std::uint32_t material = 0;
  int first = 0;  // first index
  int count = 0;  // indices
};

struct ChunkRendererStats {
  std::uint64_t uploads = 0;    // chunks uploaded into buffers
  std::uint64_t uploaded_bytes = 0;  // their vertex + index bytes, summed over every upload
  std::uint64_t evictions = 0;  // chunks evicted by the cache cap
  std::uint64_t chunks_drawn = 0;
  std::uint64_t triangles_drawn = 0;  // submitted, before clipping and discard
  std::uint64_t chunks_occluded = 0;  // skipped by draw_unoccluded() as hidden
  std::uint64_t occlusion_tests = 0;  // bounding boxes tested by draw_unoccluded()
  std::size_t cached_chunks = 0;
  std::size_t cached_bytes = 0;
  std::uint64_t texture_uploads = 0;
  std::size_t cached_textures = 0;
  std::size_t cached_texture_bytes = 0;
};

// Loads a chunk by id; the renderer calls it only for chunks it has not cached.
using ChunkLoader = std::function<std::shared_ptr<const Chunk>(std::int64_t id)>;

// Owns one GL context and the buffers of the chunks drawn with it. Chunks are
// cached by id: use one renderer per model (ids of different models collide)
// and one renderer per thread at a time. Every method makes the context
// current on the calling thread first. Results are deterministic for the same
// inputs, Mesa version and draw order.
class ChunkRenderer {
 public:
  // Takes ownership of `context`; throws std::runtime_error when the context
  // lacks OpenGL 3.3 or an entry point, or the shaders fail to build.
  explicit ChunkRenderer(std::unique_ptr<GlContext> context, ChunkRendererParams params = {});
  ~ChunkRenderer();
  ChunkRenderer(const ChunkRenderer&) = delete;
  ChunkRenderer& operator=(const ChunkRenderer&) = delete;

  // Leaves the calling thread without a current context (the next call makes
  // it current again). Call after each unit of work on a pooled thread so the
  // renderer can later be used or destroyed from any thread.
  void release_context() { context_->release_current(); }
  // The light model of every later draw (stages/shading.h); the
  // default is shading_lights(ShadingParams{}, z up). Takes effect at the next
  // draw call; the occlusion test is unaffected. Throws std::invalid_argument
  // for non-unit directions or negative or non-finite strengths.
  void set_shading(const ShadingLights& lights);
  const ShadingLights& shading() const { return lights_; }
  // The material table chunks' `materials` index (textures and alpha tests;
  // colours are already in the vertex colours) and where textures come from.
  // Drops cached textures. Without a table every triangle is untextured.
  void set_materials(std::vector<Material> materials, TextureLoader load_texture);
  // set_materials(source.materials(), source.load_texture) unless `source`'s
  // table is already in use; `source` must outlive the draws that follow.
  void use_materials_of(const ChunkSource& source);
  // True when chunk `id` has cached buffers.
  bool is_cached(std::int64_t id) const;
  // Drops every cached chunk (call when the ids' geometry changed).
  void clear_cache();

  // Starts a frame of `width` x `height` pixels (>= 1): colour cleared to
  // (0, 0, 0, 0), depth to +infinity. With `primitive_ids`, every draw of the
  // frame also records which chunk triangle drew each pixel (an integer
  // attachment, read with read_primitive_ids()); colour and depth are the
  // same either way, and frames without it pay nothing for it.
  void begin_frame(int width, int height, bool primitive_ids = false);
  // Draws the chunks `ids` in the given order, uploading through `load` those
  // not cached, with fragments strictly inside `discard_box` (world
  // coordinates; an empty box discards nothing) dropped, or with `clip` =
  // keep_inside only those kept. Throws std::logic_error without a frame,
  // std::runtime_error on a malformed chunk (indices out of range, colours not
  // one per position) naming its id.
  void draw(const RenderCamera& camera, const Box3d& discard_box, std::span<const std::int64_t> ids,
            const ChunkLoader& load, BoxClip clip = BoxClip::discard_inside);
  // Draws the same image as draw() with the chunks of `chunks` in the given
  // order, except where two surfaces tie exactly in depth, while skipping
  // chunks that are provably hidden. Pass them nearest first: after drawing a
  // batch, the bounds of every chunk not yet drawn (enlarged by a margin
  // far above float rounding) are depth-tested against what is drawn so far
  // (one instanced draw, early fragment tests, no colour or depth writes), and
  // a chunk none of whose box samples passes is dropped for good: every
  // fragment of it lies behind its box and the depth buffer only ever gets
  // nearer. Boxes that reach the near plane are never tested. Falls back to
  // drawing everything where the context lacks GL 4.3. Loads only chunks it
  // draws. Deterministic for the same inputs, renderer settings and Mesa.
  // When `drawn` is given, the ids of the chunks drawn (not skipped) are
  // appended to it in drawing order.
  void draw_unoccluded(const RenderCamera& camera, const Box3d& discard_box, std::span<const ChunkRef> chunks,
                       const ChunkLoader& load, std::vector<std::int64_t>* drawn = nullptr);
  // Loads chunk `id` through `load` and uploads it unless it is cached, as the
  // most recently used entry, without drawing it (a viewer spreads a cell's
  // uploads over frames this way). Returns the bytes uploaded (0 when it was
  // cached). Throws as draw() does for a loader that returns no or another chunk.
  std::size_t upload_ahead(std::int64_t id, const ChunkLoader& load);
  // True when draw_unoccluded() can skip hidden chunks (GL 4.3 available).
  bool occlusion_culling() const { return occlusion_program_ != 0; }
  // Same as draw(), for chunks the caller already holds (uploaded unless cached).
  void draw(const RenderCamera& camera, const Box3d& discard_box,
            std::span<const std::shared_ptr<const Chunk>> chunks, BoxClip clip = BoxClip::discard_inside);
  // Reads the frame back, row-major with row 0 at the top: RGBA8 colour and
  // planar view depth in metres (+infinity where nothing was drawn). Resizes
  // both vectors to width * height.
  void read_frame(std::vector<Rgba8>& color, std::vector<float>& depth);
  // Reads back which triangle drew each pixel of a frame begun with
  // primitive_ids, row-major with row 0 at the top: `chunk` the id of its
  // chunk (-1 where nothing was drawn) and `triangle` its number within the
  // chunk (the index into Chunk::indices / 3, whatever order the renderer
  // draws the chunk's triangles in; 0 where nothing was drawn). Resizes both
  // to width * height. Throws std::logic_error without such a frame,
  // std::runtime_error when the attachment holds a draw or triangle the frame
  // did not make.
  void read_primitive_ids(std::vector<std::int64_t>& chunk, std::vector<std::uint32_t>& triangle);

  // True when the z-test uses reversed-Z (glClipControl was available).
  bool reversed_z() const;
  // The context's GL_RENDERER string (which rasteriser or GPU draws).
  const std::string& gl_renderer() const { return gl_renderer_; }
  ChunkRendererStats stats() const;

 private:
  struct CachedChunk {
    unsigned vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
    int index_count = 0;
    unsigned index_type = 0;  // GL_UNSIGNED_SHORT or GL_UNSIGNED_INT
    Vec3d origin;
    std::size_t bytes = 0;
    std::list<std::int64_t>::iterator recency;  // position in lru_ (front = most recent)
    std::vector<ChunkDrawRange> ranges;         // the index buffer's runs per material
    // The chunk's triangle number of each triangle in the index buffer (null:
    // the same order), for primitive ids.
    std::shared_ptr<const std::vector<std::uint32_t>> triangle_of;
    std::uint32_t triangle_count = 0;
    bool appearance = false;                    // has uvs or normals: drawn with the full program
  };
  // One build of the drawing shaders and its uniform locations.
  struct DrawProgram {
    unsigned id = 0;
    int u_offset = -1, u_view_projection = -1, u_forward = -1, u_discard_lo = -1, u_discard_hi = -1,
        u_keep_inside = -1, u_lit = -1, u_key = -1, u_fill = -1, u_ambient = -1, u_textured = -1,
        u_alpha_test = -1, u_texture = -1, u_draw = -1, u_primitive_base = -1;
  };
  // A draw of a frame begun with primitive ids: its number (+ 1) is what the
  // id attachment holds.
  struct FrameDraw {
    std::int64_t id = 0;
    std::uint32_t triangle_count = 0;
    std::shared_ptr<const std::vector<std::uint32_t>> triangle_of;  // as CachedChunk's
  };

  void make_current();
  // Builds programs_[primitive_ids] (both appearances).
  void build_program(bool primitive_ids);
  // The drawing program of the current frame's kind for `appearance` (0 or 1).
  const DrawProgram& program(int appearance) const { return programs_[primitive_ids_ ? 1 : 0][appearance]; }
  void use_program(int appearance);
  void resize_framebuffer(int width, int height);
  // Throws std::runtime_error unless the bound framebuffer is complete.
  void check_framebuffer(int width, int height);
  // Adds the primitive-id attachment to the current framebuffer.
  void add_primitive_id_buffer();
  void release_framebuffer();
  const CachedChunk& upload(const Chunk& chunk);
  void evict_beyond_cap();
  void release(CachedChunk& entry);
  void set_camera_uniforms(const RenderCamera& camera, const Box3d& discard_box, BoxClip clip);
  void draw_cached(std::int64_t id, const CachedChunk& entry, const Vec3d& eye);
  // Sets the texture and alpha-test state of material `index` (unknown = untextured).
  void apply_material(std::uint32_t index);
  void draw_ids(const RenderCamera& camera, std::span<const std::int64_t> ids, const ChunkLoader& load);
  void build_occlusion_program();
  // Which of `boxes` (eye-relative lo/hi pairs) have a sample passing the depth
  // test of the current frame; one flag (0 or 1) per box.
  void test_boxes(const RenderCamera& camera, const std::vector<float>& boxes, std::vector<std::uint32_t>& visible);
  void require_frame(const char* what) const;

  std::unique_ptr<GlContext> context_;  // first member: destroyed last
  std::string gl_renderer_;
  ChunkRendererParams params_;
  std::unique_ptr<GlFunctions> gl_functions_;
  const GlFunctions& gl_;  // *gl_functions_
  // [primitive ids][appearance]: appearance 0 plain (flat normals, no
  // textures), 1 with uvs and normals; the primitive-id builds are made on
  // the first frame that asks for them.
  DrawProgram programs_[2][2];
  int active_program_ = 0;
  std::vector<Material> materials_;
  TextureLoader load_texture_;
  const ChunkSource* material_source_ = nullptr;  // whose table use_materials_of() installed
  std::unique_ptr<GlTextureCache> textures_;
  std::int64_t bound_texture_ = 0;  // texture bound to unit 0 for this draw (0 = unknown)
  bool textured_uniform_ = false, alpha_test_uniform_ = false;
  ShadingLights lights_ = shading_lights(ShadingParams{}, Vec3d{0, 0, 1});
  unsigned framebuffer_ = 0, color_buffer_ = 0, view_depth_buffer_ = 0, depth_buffer_ = 0;
  unsigned primitive_id_buffer_ =
      0;  // GL_RG32UI (draw number + 1, triangle in the draw's buffer); 0: none yet
  int frame_width_ = 0, frame_height_ = 0;
  bool in_frame_ = false;
  bool primitive_ids_ = false;  // the current frame records primitive ids
  std::vector<FrameDraw> frame_draws_;
  std::unordered_map<std::int64_t, CachedChunk> cache_;
  std::list<std::int64_t> lru_;
  std::size_t cached_bytes_ = 0;
  ChunkRendererStats stats_;
  unsigned occlusion_program_ = 0;  // 0: occlusion culling unavailable
  int u_occlusion_view_projection_ = -1;
  unsigned occlusion_vertex_array_ = 0, occlusion_corners_ = 0, occlusion_indices_ = 0, occlusion_boxes_ = 0,
           occlusion_flags_ = 0;
  std::size_t occlusion_capacity_ = 0;  // boxes the instance and flag buffers hold
  std::vector<float> readback_depth_;
  std::vector<Rgba8> readback_color_;
  std::vector<std::uint32_t> readback_ids_;
};

}  // namespace cellbake
