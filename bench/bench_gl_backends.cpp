// EGL vs OSMesa (issue #12): the same 512^2 x 6 cube maps of real cells of a
// geometry store through the sample stage (stages/sample/sample.h), once per GL
// backend, side by side in one run. Same cells and cull boxes as bench_sample's
// BM_SampleStore (cull_box stage, 4 m cells); one renderer per backend kept
// across cells, caches warmed by one untimed pass. Run as
//   CELLBAKE_BENCH_STORE=/tmp/h2/plant.store.db LP_NUM_THREADS=1
//     build/bench/bench_gl_backends --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
// and compare the medians: interleaved repetitions share the machine's load
// fairly, and the process CPU time (all llvmpipe threads) is the steadier
// figure on a shared machine. Both backends are llvmpipe here (EGL takes the
// default device choice, so on a GPU machine it runs on the GPU).
// BM_CreateContext times one context's creation and destruction per backend.
// BM_RawGlCubeMapStore is the floor under any GL sampler on the same device
// and cells (issue #12's "raw GL" figure): every triangle of the store in one
// vertex and one index buffer uploaded once, each face drawing the chunks
// chunks_in_face() lists (the sampler's frustum selection, made untimed) as
// one glDrawElements each, with a plain shader (vertex colour, planar depth;
// no discard box, occlusion tests, lighting or per-chunk uniforms), then the
// same RGBA8 + R32F read-back (argument 1) or a glFinish instead (argument 0).
// BM_CubeMapStore / BM_RawGlCubeMapStore/1 is the sampler's overhead there.
// BM_PrimitiveIdPassStore/1 against /0: what the seen triangles (issue #35) add.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bench/bench_store_eyes.h"
#include "stages/cube_map.h"
#include "stages/cull_box.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_sample_cube.h"
#include "stages/render/gl_functions.h"
#include "stages/sample/sample.h"
#include "stages/far/seen_triangles.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

GlBackend backend_of(const benchmark::State& state) { return static_cast<GlBackend>(state.range(0)); }

void BM_CreateContext(benchmark::State& state) {
  const GlBackend backend = backend_of(state);
  if (!gl_backend_compiled(backend)) {
    state.SkipWithError("backend not in this build");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(create_gl_context(backend, 1, 1));
  state.SetLabel(gl_backend_name(backend));
}
BENCHMARK(BM_CreateContext)
    ->Arg(static_cast<int>(GlBackend::osmesa))
    ->Arg(static_cast<int>(GlBackend::egl))
    ->Unit(benchmark::kMillisecond);

// The store CELLBAKE_BENCH_STORE names, or nullptr with `state` marked skipped.
const char* bench_store_path(benchmark::State& state) {
  const char* path = std::getenv("CELLBAKE_BENCH_STORE");
  if (!path) state.SkipWithError("CELLBAKE_BENCH_STORE is not set");
  return path;
}

// bench_sample's cells on `store`: each eye of bench_eyes() with the cull box
// the cull_box stage finds for 4 m cells (as configs/plant-demo.toml).
std::vector<std::pair<Vec3d, Box3d>> bench_cells(const GeometryStore& store) {
  std::vector<std::pair<Vec3d, Box3d>> cells;
  for (const Vec3d& eye : bench_eyes(store.model_bounds())) {
    CullBoxParams cull;
    cull.min_half_size = 2.0;
    cells.emplace_back(eye, Box3d::cube(eye, find_cull_box(eye, cull, store).half_size));
  }
  return cells;
}

void BM_CubeMapStore(benchmark::State& state) {
  const GlBackend backend = backend_of(state);
  const char* path = bench_store_path(state);
  if (!path) return;
  if (!gl_backend_compiled(backend)) {
    state.SkipWithError("backend not in this build");
    return;
  }
  const GeometryStore store(path);
  const std::vector<std::pair<Vec3d, Box3d>> cells = bench_cells(store);
  SampleParams params;
  params.face_size = 512;
  ChunkRenderer renderer(create_gl_context(backend, 1, 1));
  for (const auto& [eye, cull_box] : cells) sample_cube(eye, cull_box, params, store, renderer);  // warm caches
  const ChunkRendererStats before = renderer.stats();
  CubeSample last;
  for (auto _ : state)
    for (const auto& [eye, cull_box] : cells) last = sample_cube(eye, cull_box, params, store, renderer);
  // A check that the faces hold what they should, beside the raw figure's.
  std::size_t covered = 0;
  for (const CubeFace& face : last.faces)
    covered += std::count_if(face.depth.begin(), face.depth.end(), [](float d) { return d < 1e29f; });
  state.counters["covered"] = static_cast<double>(covered) / (6.0 * params.face_size * params.face_size);
  const double cube_maps = static_cast<double>(state.iterations() * cells.size());
  state.SetLabel(gl_backend_name(backend));
  state.counters["cells"] = static_cast<double>(cells.size());
  state.counters["s_per_cube"] = benchmark::Counter(cube_maps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["tris_drawn_per_cube"] =
      static_cast<double>(renderer.stats().triangles_drawn - before.triangles_drawn) / cube_maps;
}
// One iteration is one pass over all cells; s_per_cube is the wall time per cube map.
BENCHMARK(BM_CubeMapStore)
    ->Arg(static_cast<int>(GlBackend::osmesa))
    ->Arg(static_cast<int>(GlBackend::egl))
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(1);

// The cost of the primitive-id pass (issue #35): the sampler's faces of the
// same cells (chunks_in_face(), drawn through draw_unoccluded() and read
// back) without (argument 0) and with (argument 1) the primitive-id
// attachment, its read-back and the seen triangles made from it. OSMesa.
void BM_PrimitiveIdPassStore(benchmark::State& state) {
  const bool primitive_ids = state.range(0) != 0;
  const char* path = bench_store_path(state);
  if (!path) return;
  if (!gl_backend_compiled(GlBackend::osmesa)) {
    state.SkipWithError("OSMesa not in this build");
    return;
  }
  const GeometryStore store(path);
  const std::vector<std::pair<Vec3d, Box3d>> cells = bench_cells(store);
  constexpr int kSize = 512;
  ChunkRenderer renderer(create_gl_context(GlBackend::osmesa, 1, 1));
  renderer.use_materials_of(store);
  const ChunkLoader load = [&store](std::int64_t id) { return store.load(id); };
  std::vector<std::vector<ChunkRef>> faces;
  for (const auto& [eye, cull_box] : cells)
    for (int face = 0; face < kCubeFaces; ++face)
      faces.push_back(chunks_in_face(face, eye, cull_box, 0.01, store));
  const std::vector<std::uint32_t> tiles = pixel_tiles(kSize);
  SeenScratch scratch;
  std::vector<Rgba8> color;
  std::vector<float> depth;
  std::vector<std::int64_t> chunk;
  std::vector<std::uint32_t> triangle;
  std::size_t seen = 0;
  const auto pass = [&] {
    std::size_t k = 0;
    for (const auto& [eye, cull_box] : cells)
      for (int face = 0; face < kCubeFaces; ++face) {
        renderer.begin_frame(kSize, kSize, primitive_ids);
        renderer.draw_unoccluded(cube_face_camera(eye, face), cull_box, faces[k++], load);
        renderer.read_frame(color, depth);
        if (!primitive_ids) continue;
        renderer.read_primitive_ids(chunk, triangle);
        seen += seen_triangles(chunk, triangle, tiles, scratch).size();
      }
  };
  pass();  // warm caches
  for (auto _ : state) pass();
  const double cube_maps = static_cast<double>(state.iterations() * cells.size());
  state.SetLabel(primitive_ids ? "with primitive ids" : "without");
  state.counters["s_per_cube"] =
      benchmark::Counter(cube_maps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  benchmark::DoNotOptimize(seen);
}
BENCHMARK(BM_PrimitiveIdPassStore)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(1);

constexpr const char* kRawVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec4 a_color;
uniform vec3 u_offset;  // model centre - eye
uniform mat4 u_view_projection;
uniform vec3 u_forward;
out vec4 v_color;
out float v_view_depth;
void main() {
  vec3 relative = a_position + u_offset;
  v_color = a_color;
  v_view_depth = dot(relative, u_forward);
  gl_Position = u_view_projection * vec4(relative, 1.0);
}
)";
constexpr const char* kRawFragmentShader = R"(#version 330 core
in vec4 v_color;
in float v_view_depth;
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_view_depth;
void main() {
  o_color = v_color;
  o_view_depth = v_view_depth;
}
)";

// The whole store in one vertex buffer (float positions relative to the
// model's centre) and one index buffer; `ranges[id]` is chunk id's run of it.
struct RawGlScene {
  Vec3d centre;
  GLuint vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
  std::unordered_map<std::int64_t, std::pair<std::size_t, GLsizei>> ranges;  // first index, count
  std::size_t triangles = 0;
};

RawGlScene upload_raw_scene(const GlFunctions& gl, const GeometryStore& store) {
  RawGlScene scene;
  scene.centre = store.model_bounds().center();
  std::vector<Vec3f> positions;
  std::vector<Rgba8> colors;
  std::vector<std::uint32_t> indices;
  for (const ChunkRef& ref : store.query(store.model_bounds())) {
    const std::shared_ptr<const Chunk> chunk = store.load(ref.id);
    const std::uint32_t base = static_cast<std::uint32_t>(positions.size());
    for (std::uint32_t v = 0; v < chunk->positions.size(); ++v) {
      const Vec3d p = chunk->world(v) - scene.centre;
      positions.push_back({static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    }
    colors.insert(colors.end(), chunk->colors.begin(), chunk->colors.end());
    scene.ranges[ref.id] = {indices.size(), static_cast<GLsizei>(chunk->indices.size())};
    for (std::uint32_t i : chunk->indices) indices.push_back(base + i);
  }
  scene.triangles = indices.size() / 3;
  gl.GenVertexArrays(1, &scene.vertex_array);
  gl.BindVertexArray(scene.vertex_array);
  gl.GenBuffers(1, &scene.vertex_buffer);
  gl.BindBuffer(GL_ARRAY_BUFFER, scene.vertex_buffer);
  const std::size_t position_bytes = positions.size() * sizeof(Vec3f);
  gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(position_bytes + colors.size() * sizeof(Rgba8)),
                nullptr, GL_STATIC_DRAW);
  gl.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(position_bytes), positions.data());
  gl.BufferSubData(GL_ARRAY_BUFFER, static_cast<GLintptr>(position_bytes),
                   static_cast<GLsizeiptr>(colors.size() * sizeof(Rgba8)), colors.data());
  gl.EnableVertexAttribArray(0);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vec3f), nullptr);
  gl.EnableVertexAttribArray(1);
  gl.VertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(Rgba8),
                         reinterpret_cast<const void*>(position_bytes));
  gl.GenBuffers(1, &scene.index_buffer);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, scene.index_buffer);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                indices.data(), GL_STATIC_DRAW);
  check_gl_error(gl, "bench raw GL: upload");
  return scene;
}

void BM_RawGlCubeMapStore(benchmark::State& state) {
  const bool read_back = state.range(0) != 0;
  const char* path = bench_store_path(state);
  if (!path) return;
  const GeometryStore store(path);
  const std::vector<std::pair<Vec3d, Box3d>> cells = bench_cells(store);
  SampleParams params;
  params.face_size = 512;
  const int size = params.face_size;
  // Each cell's six faces: the chunks the sampler would consider.
  std::vector<std::array<std::vector<std::int64_t>, kCubeFaces>> face_chunks(cells.size());
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (int face = 0; face < kCubeFaces; ++face)
      for (const ChunkRef& ref :
           chunks_in_face(face, cells[c].first, cells[c].second, params.near_plane, store))
        face_chunks[c][face].push_back(ref.id);

  const std::unique_ptr<GlContext> context = create_gl_context(GlBackend::egl, 1, 1);
  const GlFunctions gl = load_gl_functions(*context);
  const RawGlScene scene = upload_raw_scene(gl, store);
  const GLuint program = build_gl_program(gl, kRawVertexShader, kRawFragmentShader, "bench raw GL");
  const GLint u_offset = gl.GetUniformLocation(program, "u_offset");
  const GLint u_view_projection = gl.GetUniformLocation(program, "u_view_projection");
  const GLint u_forward = gl.GetUniformLocation(program, "u_forward");
  GLuint framebuffer = 0;
  gl.GenFramebuffers(1, &framebuffer);
  gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  std::array<GLuint, 3> renderbuffers{};
  gl.GenRenderbuffers(3, renderbuffers.data());
  const std::array<std::pair<GLenum, GLenum>, 3> attachments = {
      std::pair{GL_RGBA8, GL_COLOR_ATTACHMENT0}, std::pair{GL_R32F, GL_COLOR_ATTACHMENT1},
      std::pair{GL_DEPTH_COMPONENT32F, GL_DEPTH_ATTACHMENT}};
  for (int i = 0; i < 3; ++i) {
    gl.BindRenderbuffer(GL_RENDERBUFFER, renderbuffers[i]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, attachments[i].first, size, size);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, attachments[i].second, GL_RENDERBUFFER, renderbuffers[i]);
  }
  if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("bench raw GL: framebuffer incomplete");
  const GLenum draw_buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl.DrawBuffers(2, draw_buffers);
  gl.Viewport(0, 0, size, size);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.Disable(GL_CULL_FACE);
  gl.UseProgram(program);
  gl.BindVertexArray(scene.vertex_array);
  check_gl_error(gl, "bench raw GL: setup");

  std::vector<Rgba8> color(static_cast<std::size_t>(size) * size);
  std::vector<float> depth(color.size());
  std::uint64_t triangles_drawn = 0;
  std::size_t covered = 0;  // pixels drawn in the last cube map (read-back only)
  const auto cube_map = [&](std::size_t c) {
    covered = 0;
    const Vec3d& eye = cells[c].first;
    for (int face = 0; face < kCubeFaces; ++face) {
      const FaceBasis b = cube_face_basis(face);
      const RenderCamera camera = cube_face_camera(eye, face, params.near_plane);
      const std::array<float, 16> view_projection = camera_view_projection(camera, false);
      const Vec3d offset = scene.centre - eye;
      const float clear_color[4] = {0, 0, 0, 0}, clear_view_depth[4] = {1e30f, 0, 0, 0}, clear_depth = 1.0f;
      gl.ClearBufferfv(GL_COLOR, 0, clear_color);
      gl.ClearBufferfv(GL_COLOR, 1, clear_view_depth);
      gl.ClearBufferfv(GL_DEPTH, 0, &clear_depth);
      gl.Uniform3f(u_offset, static_cast<float>(offset.x), static_cast<float>(offset.y),
                   static_cast<float>(offset.z));
      gl.Uniform3f(u_forward, static_cast<float>(b.forward.x), static_cast<float>(b.forward.y),
                   static_cast<float>(b.forward.z));
      gl.UniformMatrix4fv(u_view_projection, 1, GL_FALSE, view_projection.data());
      for (std::int64_t id : face_chunks[c][face]) {
        const auto& [first, count] = scene.ranges.at(id);
        gl.DrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT,
                        reinterpret_cast<const void*>(first * sizeof(std::uint32_t)));
        triangles_drawn += static_cast<std::uint64_t>(count) / 3;
      }
      if (read_back) {
        gl.ReadBuffer(GL_COLOR_ATTACHMENT0);
        gl.ReadPixels(0, 0, size, size, GL_RGBA, GL_UNSIGNED_BYTE, color.data());
        gl.ReadBuffer(GL_COLOR_ATTACHMENT1);
        gl.ReadPixels(0, 0, size, size, GL_RED, GL_FLOAT, depth.data());
        covered += std::count_if(depth.begin(), depth.end(), [](float d) { return d < 1e29f; });
      }
    }
    if (!read_back) gl.Finish();
  };
  for (std::size_t c = 0; c < cells.size(); ++c) cube_map(c);  // warm-up
  check_gl_error(gl, "bench raw GL: draw");
  triangles_drawn = 0;
  for (auto _ : state)
    for (std::size_t c = 0; c < cells.size(); ++c) cube_map(c);
  benchmark::DoNotOptimize(color.data());
  const double cube_maps = static_cast<double>(state.iterations() * cells.size());
  state.SetLabel(std::string("egl raw: ") + reinterpret_cast<const char*>(gl.GetString(GL_RENDERER)));
  state.counters["cells"] = static_cast<double>(cells.size());
  state.counters["store_tris"] = static_cast<double>(scene.triangles);
  state.counters["s_per_cube"] =
      benchmark::Counter(cube_maps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["tris_drawn_per_cube"] = static_cast<double>(triangles_drawn) / cube_maps;
  if (read_back) state.counters["covered"] = static_cast<double>(covered) / (6.0 * size * size);
  gl.DeleteFramebuffers(1, &framebuffer);
  gl.DeleteRenderbuffers(3, renderbuffers.data());
  gl.DeleteProgram(program);
  gl.DeleteVertexArrays(1, &scene.vertex_array);
  gl.DeleteBuffers(1, &scene.vertex_buffer);
  gl.DeleteBuffers(1, &scene.index_buffer);
}
// One iteration is one pass over all cells, as BM_CubeMapStore.
BENCHMARK(BM_RawGlCubeMapStore)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace cellbake

BENCHMARK_MAIN();
