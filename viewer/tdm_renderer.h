// Draws textured depth meshes (Wilson 2002, ch. 4–5: the far field of a view
// cell, one mesh per cube face of a panoramic sample, textured with that
// face's colour image) into the frame a ChunkRenderer on the same GL context
// has begun: same camera matrix, same depth convention, same two colour
// attachments (RGBA8 colour + planar view depth), so meshes and chunks
// depth-test against each other.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>

#include "stages/cube_map.h"
#include "stages/encode/encode.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"

namespace cellbake {

struct GlFunctions;

struct TdmDrawOptions {
  bool wireframe = false;
  // Mixed into the texture colour: rgb * (1 - tint.a) + tint.rgb * tint.a (0..1).
  float tint[4] = {0, 0, 0, 0};
};

// Owns the GPU copies (vertex array, buffers, texture) of uploaded face meshes.
// Shares `context` with the ChunkRenderer that begins and reads the frames;
// every method makes it current first. One thread at a time.
class TdmRenderer {
 public:
  // Throws std::runtime_error when the context lacks an entry point or the
  // shaders fail to build.
  explicit TdmRenderer(std::shared_ptr<GlContext> context);
  ~TdmRenderer();
  TdmRenderer(const TdmRenderer&) = delete;
  TdmRenderer& operator=(const TdmRenderer&) = delete;

  // Uploads one face: `mesh` positions relative to `sample_eye` (world), uvs
  // into `image` (u right, v down). Returns a handle (> 0) for draw/erase.
  // Throws std::invalid_argument for an empty image or uvs not one per
  // position, std::runtime_error for an index out of range.
  std::uint64_t upload(const FaceMesh& mesh, const DecodedImage& image, const Vec3d& sample_eye);
  // Frees one upload (unknown handles are ignored).
  void erase(std::uint64_t handle);
  // Draws the uploads `handles` into the current frame of the ChunkRenderer
  // sharing the context (call between its begin_frame and read_frame),
  // depth-tested against what is there. `reversed_z` must be that renderer's
  // reversed_z(). Returns the triangles submitted. Throws std::out_of_range
  // for an unknown handle.
  std::uint64_t draw(const RenderCamera& camera, bool reversed_z, std::span<const std::uint64_t> handles,
                     const TdmDrawOptions& options = {});
  // One range of an upload's triangles: indices [first_index, first_index + index_count).
  struct Range {
    std::uint64_t handle = 0;
    std::uint32_t first_index = 0, index_count = 0;
  };
  // As above, drawing only the given index ranges (e.g. the tiles of a face
  // mesh the camera can see). Throws std::out_of_range for an unknown handle
  // or a range past the upload's indices.
  std::uint64_t draw_ranges(const RenderCamera& camera, bool reversed_z, std::span<const Range> ranges,
                            const TdmDrawOptions& options = {});
  // Bytes held by uploads (vertex, index and texture data).
  std::size_t gpu_bytes() const { return bytes_; }
  // Bytes uploaded so far, summed over every upload (freed ones included).
  std::uint64_t uploaded_bytes() const { return uploaded_bytes_; }

 private:
  struct Upload {
    unsigned vertex_array = 0, vertex_buffer = 0, index_buffer = 0, texture = 0;
    int index_count = 0;
    Vec3d eye;
    std::size_t bytes = 0;
  };
  void free(Upload& u);

  std::shared_ptr<GlContext> context_;
  std::unique_ptr<GlFunctions> gl_;
  unsigned program_ = 0;
  int u_offset_ = -1, u_view_projection_ = -1, u_forward_ = -1, u_image_ = -1, u_tint_ = -1;
  std::unordered_map<std::uint64_t, Upload> uploads_;
  std::uint64_t next_handle_ = 1;
  std::size_t bytes_ = 0;
  std::uint64_t uploaded_bytes_ = 0;
};

}  // namespace cellbake
