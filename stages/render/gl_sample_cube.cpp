// The GL backend's cube map: each face drawn nearest first through
// ChunkRenderer::draw_unoccluded(), its primitive ids read back as seen lists.
#include "stages/render/gl_sample_cube.h"

#include <cstdint>
#include <vector>

#include "stages/far/seen_triangles.h"

namespace cellbake {

CubeSample sample_cube(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                       const ChunkSource& source, ChunkRenderer& renderer) {
  validate_sample_inputs(eye, params);
  renderer.use_materials_of(source);
  const int render_size = params.face_size * params.supersample;
  const ChunkLoader load = [&source](std::int64_t id) { return source.load(id); };
  CubeSample sample;
  sample.eye = eye;
  std::vector<Rgba8> color;
  std::vector<float> depth;
  std::vector<std::int64_t> pixel_chunk;
  std::vector<std::uint32_t> pixel_triangle;
  const std::vector<std::uint32_t> tiles = pixel_tiles(render_size);
  SeenScratch scratch;
  for (int face = 0; face < kCubeFaces; ++face) {
    // Nearest first, so that the renderer can skip chunks hidden behind those drawn before.
    const std::vector<ChunkRef> nearest_first =
        chunks_in_face_nearest_first(face, eye, cull_box, params.near_plane, source);
    const RenderCamera camera = cube_face_camera(eye, face, params.near_plane);
    renderer.begin_frame(render_size, render_size, /*primitive_ids=*/true);
    renderer.draw_unoccluded(camera, cull_box, nearest_first, load);
    renderer.read_frame(color, depth);
    renderer.read_primitive_ids(pixel_chunk, pixel_triangle);
    CubeFace& out = sample.faces[static_cast<std::size_t>(face)];
    out = finish_face(color, depth, params);
    // Seen: the triangles that drew pixels, each with the tiles of its
    // (render-resolution) pixels, as the ray-casting backend reports them.
    out.seen = seen_triangles(pixel_chunk, pixel_triangle, tiles, scratch);
  }
  return sample;
}

}  // namespace cellbake
