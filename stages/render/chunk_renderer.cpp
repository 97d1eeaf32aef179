#include "stages/render/chunk_renderer.h"

#include "stages/render/gl_functions.h"
#include "stages/render/gl_texture_cache.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

// Vertex shader: positions arrive relative to the chunk origin; u_offset moves
// them to eye-relative world axes; u_view_projection = projection * rotation
// into the camera frame.
constexpr const char* kVertexShader = R"(
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec4 a_color;
layout(location = 2) in vec2 a_uv;      // (0, 0) when the chunk has none
layout(location = 3) in vec4 a_normal;  // (0, 0, 0) when the chunk has none: flat
uniform vec3 u_offset;      // chunk origin - eye, world axes
uniform mat4 u_view_projection;
uniform vec3 u_forward;     // camera forward axis, unit length
out vec3 v_relative;        // world position - eye
out float v_view_depth;     // planar distance along the camera's forward axis
out vec4 v_color;
out vec2 v_uv;
out vec3 v_normal;
void main() {
  v_relative = a_position + u_offset;
  v_view_depth = dot(v_relative, u_forward);
  v_color = a_color;
  v_uv = a_uv;
  v_normal = a_normal.xyz;
  gl_Position = u_view_projection * vec4(v_relative, 1.0);
}
)";

// The light model of stages/shading.h: the interpolated vertex normal
// when the chunk has normals, else a flat face normal from the screen-space
// derivatives of the eye-relative position (exact for planar triangles, in
// world axes); two-sided Lambert over two lights plus ambient. A fragment
// whose derivatives give no normal keeps its base colour. The base colour is
// the vertex colour times the material's texel (trilinear, mipmapped) when the
// material has a texture; alpha-tested materials drop texels below 0.5 alpha.
// Built twice: with APPEARANCE 1 for chunks with texture coordinates or
// normals, and with APPEARANCE 0 (no texture lookup, flat normals only) for
// the rest, where llvmpipe would otherwise pay for the unused paths; and each
// again with PRIMITIVE_IDS 1 for frames that record which triangle drew each
// pixel: (draw number + 1, triangle within the draw's index buffer) into an
// integer attachment. gl_PrimitiveID counts from 0 in each glDrawElements, so
// u_primitive_base adds the draw's first triangle.
constexpr const char* kFragmentShader = R"(
in vec3 v_relative;
in float v_view_depth;
in vec4 v_color;
in vec2 v_uv;
in vec3 v_normal;
uniform vec3 u_discard_lo;  // discard box relative to the eye
uniform vec3 u_discard_hi;
uniform int u_keep_inside;  // 0: drop fragments inside the box, 1: keep only those
uniform int u_lit;          // 0: base colour as it is
uniform vec3 u_key;         // unit light directions, world axes, times their strengths
uniform vec3 u_fill;
uniform float u_ambient;
uniform int u_textured;     // 1: multiply by u_texture at v_uv
uniform int u_alpha_test;   // 1: drop fragments whose texel alpha < 0.5
uniform sampler2D u_texture;
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_view_depth;
#if PRIMITIVE_IDS
uniform int u_draw;            // the draw's number in the frame + 1
uniform int u_primitive_base;  // its first triangle in the chunk's index buffer
layout(location = 2) out uvec2 o_primitive;
#endif
void main() {
  // Derivatives and texture lookups before any discard (uniform control flow;
  // an if on a uniform, not a select, so untextured draws skip the lookup).
  vec3 flat_normal = cross(dFdx(v_relative), dFdy(v_relative));
  vec4 texel = vec4(1.0);
#if APPEARANCE
  if (u_textured != 0) texel = texture(u_texture, v_uv);
#endif
  bool inside = all(greaterThan(v_relative, u_discard_lo)) && all(lessThan(v_relative, u_discard_hi));
  if (inside != (u_keep_inside != 0)) discard;
  if (u_alpha_test != 0 && texel.a < 0.5) discard;
  vec4 base = v_color * vec4(texel.rgb, 1.0);
  vec3 color = base.rgb;
  if (u_lit != 0) {
    vec3 n = flat_normal;
#if APPEARANCE
    if (dot(v_normal, v_normal) > 1e-6) n = v_normal;
#endif
    float n2 = dot(n, n);
    if (n2 > 0.0 && !isinf(n2)) {
      n *= inversesqrt(n2);
      color = clamp(color * (u_ambient + abs(dot(n, u_key)) + abs(dot(n, u_fill))), 0.0, 1.0);
    }
  }
  o_color = vec4(color, base.a);
  o_view_depth = v_view_depth;
#if PRIMITIVE_IDS
  o_primitive = uvec2(uint(u_draw), uint(u_primitive_base + gl_PrimitiveID));
#endif
}
)";

// Occlusion test of chunk bounds (GL 4.3): instanced unit cubes stretched to
// eye-relative boxes; with early fragment tests only fragments that pass the
// depth test run the fragment shader, which flags the box as visible.
constexpr const char* kOcclusionVertexShader = R"(#version 430 core
layout(location = 0) in vec3 a_corner;  // unit cube corner, 0 or 1 per axis
layout(location = 1) in vec3 a_lo;      // per instance: box relative to the eye
layout(location = 2) in vec3 a_hi;
uniform mat4 u_view_projection;
flat out int v_box;
void main() {
  v_box = gl_InstanceID;
  gl_Position = u_view_projection * vec4(mix(a_lo, a_hi, a_corner), 1.0);
}
)";

constexpr const char* kOcclusionFragmentShader = R"(#version 430 core
layout(early_fragment_tests) in;
flat in int v_box;
layout(std430, binding = 0) buffer Visible { uint visible[]; };
void main() { visible[v_box] = 1u; }
)";

// The first batch draw_unoccluded() draws untested; later batches double.
constexpr std::size_t kFirstUntestedBatch = 64;

struct Vertex {
  float x, y, z;
  Rgba8 color;
};
static_assert(sizeof(Vertex) == 16);

// The layout of chunks with texture coordinates or normals: the normal packed
// as GL_INT_2_10_10_10_REV (signed normalised, w unused).
struct VertexExtended {
  float x, y, z;
  Rgba8 color;
  float u, v;
  std::uint32_t normal;
};
static_assert(sizeof(VertexExtended) == 28);

std::uint32_t pack_normal_2_10_10_10(const Vec3f& n) {
  const auto component = [](float v) {
    const long q = std::lround(std::clamp(std::isfinite(v) ? v : 0.f, -1.f, 1.f) * 511.f);
    return static_cast<std::uint32_t>(q) & 0x3FFu;
  };
  return component(n.x) | (component(n.y) << 10) | (component(n.z) << 20);
}

// Triangle order of a chunk's draw: grouped by material (stable), as ranges;
// `triangle_of` the chunk's triangle number of each triangle drawn, left
// empty when that is the chunk's own order.
std::vector<std::uint32_t> order_by_material(const Chunk& chunk, std::vector<ChunkDrawRange>& ranges,
                                             std::vector<std::uint32_t>& triangle_of) {
  const std::size_t triangles = chunk.indices.size() / 3;
  ranges.clear();
  triangle_of.clear();
  if (chunk.materials.empty()) {
    ranges.push_back({0, 0, static_cast<int>(chunk.indices.size())});
    return chunk.indices;
  }
  std::vector<std::uint32_t> order(triangles);
  for (std::size_t t = 0; t < triangles; ++t) order[t] = static_cast<std::uint32_t>(t);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return chunk.materials[a] < chunk.materials[b]; });
  std::vector<std::uint32_t> indices;
  indices.reserve(chunk.indices.size());
  for (std::size_t k = 0; k < triangles; ++k) {
    const std::uint32_t t = order[k];
    if (ranges.empty() || ranges.back().material != chunk.materials[t])
      ranges.push_back({chunk.materials[t], static_cast<int>(indices.size()), 0});
    for (int c = 0; c < 3; ++c) indices.push_back(chunk.indices[3 * t + c]);
    ranges.back().count += 3;
  }
  if (!std::is_sorted(order.begin(), order.end())) triangle_of = std::move(order);
  return indices;
}

// Column-major 4x4 matrices as GL expects them; built in double.
using Mat4 = std::array<double, 16>;

Mat4 multiply(const Mat4& a, const Mat4& b) {
  Mat4 m{};
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) m[col * 4 + row] += a[k * 4 + row] * b[col * 4 + k];
  return m;
}

// Rotation from world axes to the camera frame (rows right, up, -forward).
Mat4 view_rotation(const RenderCamera& c) {
  Mat4 m{};
  const Vec3d rows[3] = {c.right, c.up, c.forward * -1.0};
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) m[k * 4 + r] = rows[r][k];
  m[15] = 1;
  return m;
}

// Off-axis perspective with an infinite far plane. Reversed-Z (clip control
// ZERO_TO_ONE): depth = near / d, 1 at the near plane, -> 0 at infinity.
// Standard: NDC z = 1 - 2 near / d.
Mat4 projection(const RenderCamera& c, bool reversed_z) {
  const double l = c.tan_left, r = c.tan_right, b = c.tan_bottom, t = c.tan_top, n = c.near_plane;
  Mat4 m{};
  m[0] = 2 / (r - l);
  m[8] = (r + l) / (r - l);
  m[5] = 2 / (t - b);
  m[9] = (t + b) / (t - b);
  m[11] = -1;
  if (reversed_z) {
    m[14] = n;
  } else {
    m[10] = -1;
    m[14] = -2 * n;
  }
  return m;
}

void validate_camera(const RenderCamera& c) {
  if (!is_finite(c.eye)) throw std::invalid_argument("chunk_renderer: camera eye is not finite");
  if (!(c.near_plane > 0) || !std::isfinite(c.near_plane))
    throw std::invalid_argument("chunk_renderer: near plane must be positive, got " + std::to_string(c.near_plane));
  if (!(c.tan_right > c.tan_left) || !(c.tan_top > c.tan_bottom))
    throw std::invalid_argument("chunk_renderer: empty camera frustum");
}

// Makes `context` current and loads its entry points.
GlFunctions load_current_functions(GlContext* context) {
  if (!context) throw std::invalid_argument("chunk_renderer: null GL context");
  context->make_current();
  return load_gl_functions(*context);
}

}  // namespace

std::array<float, 16> camera_view_projection(const RenderCamera& camera, bool reversed_z) {
  validate_camera(camera);
  const Mat4 view_projection = multiply(projection(camera, reversed_z), view_rotation(camera));
  std::array<float, 16> matrix;
  std::transform(view_projection.begin(), view_projection.end(), matrix.begin(),
                 [](double v) { return static_cast<float>(v); });
  return matrix;
}

ChunkRenderer::ChunkRenderer(std::unique_ptr<GlContext> context, ChunkRendererParams params)
    : context_(std::move(context)),
      params_(params),
      gl_functions_(std::make_unique<GlFunctions>(load_current_functions(context_.get()))),
      gl_(*gl_functions_) {
  build_program(false);
  build_occlusion_program();
  textures_ = std::make_unique<GlTextureCache>(gl_, params_.texture_cache_bytes);
  if (const auto* name = reinterpret_cast<const char*>(gl_.GetString(GL_RENDERER))) gl_renderer_ = name;
}

ChunkRenderer::~ChunkRenderer() {
  try {
    make_current();
    clear_cache();
    textures_.reset();
    release_framebuffer();
    for (const auto& set : programs_)
      for (const DrawProgram& p : set)
        if (p.id) gl_.DeleteProgram(p.id);
    if (occlusion_program_) {
      gl_.DeleteProgram(occlusion_program_);
      gl_.DeleteVertexArrays(1, &occlusion_vertex_array_);
      const GLuint buffers[] = {occlusion_corners_, occlusion_indices_, occlusion_boxes_, occlusion_flags_};
      gl_.DeleteBuffers(4, buffers);
    }
  } catch (...) {
    // The context goes away with us; its objects go with it.
  }
}

// Unconditional: another context may have been made current on this thread,
// or this one on another thread, since the last call (a pointer comparison
// with OSMesaGetCurrentContext cannot tell a reused address apart).
void ChunkRenderer::make_current() { context_->make_current(); }

void ChunkRenderer::build_program(bool primitive_ids) {
  for (int appearance = 0; appearance < 2; ++appearance) {
    const std::string header = std::string("#version 330 core\n#define APPEARANCE ") +
                               (appearance ? "1" : "0") + "\n#define PRIMITIVE_IDS " +
                               (primitive_ids ? "1" : "0") + "\n";
    DrawProgram& p = programs_[primitive_ids ? 1 : 0][appearance];
    p.id = build_gl_program(gl_, (header + kVertexShader).c_str(), (header + kFragmentShader).c_str(), "chunk_renderer");
    const auto at = [&](const char* name) { return gl_.GetUniformLocation(p.id, name); };
    p.u_offset = at("u_offset");
    p.u_view_projection = at("u_view_projection");
    p.u_forward = at("u_forward");
    p.u_discard_lo = at("u_discard_lo");
    p.u_discard_hi = at("u_discard_hi");
    p.u_keep_inside = at("u_keep_inside");
    p.u_lit = at("u_lit");
    p.u_key = at("u_key");
    p.u_fill = at("u_fill");
    p.u_ambient = at("u_ambient");
    p.u_textured = at("u_textured");
    p.u_alpha_test = at("u_alpha_test");
    p.u_texture = at("u_texture");
    p.u_draw = at("u_draw");
    p.u_primitive_base = at("u_primitive_base");
  }
  check_gl_error(gl_, "chunk_renderer: build_program");
}

void ChunkRenderer::use_program(int appearance) {
  if (active_program_ == appearance) return;
  active_program_ = appearance;
  gl_.UseProgram(program(appearance).id);
}

void ChunkRenderer::build_occlusion_program() {
  if (!gl_.MemoryBarrier) return;  // no GL 4.3: draw_unoccluded() draws everything
  occlusion_program_ = build_gl_program(gl_, kOcclusionVertexShader, kOcclusionFragmentShader, "chunk_renderer");
  u_occlusion_view_projection_ = gl_.GetUniformLocation(occlusion_program_, "u_view_projection");
  static constexpr float corners[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
  static constexpr std::uint8_t faces[36] = {0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3, 0, 4, 5, 0, 5, 1,
                                             2, 3, 7, 2, 7, 6, 0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5};
  gl_.GenVertexArrays(1, &occlusion_vertex_array_);
  gl_.BindVertexArray(occlusion_vertex_array_);
  GLuint buffers[4] = {0, 0, 0, 0};
  gl_.GenBuffers(4, buffers);
  occlusion_corners_ = buffers[0], occlusion_indices_ = buffers[1], occlusion_boxes_ = buffers[2],
  occlusion_flags_ = buffers[3];
  gl_.BindBuffer(GL_ARRAY_BUFFER, occlusion_corners_);
  gl_.BufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  gl_.BindBuffer(GL_ARRAY_BUFFER, occlusion_boxes_);
  for (GLuint attribute : {1u, 2u}) {
    gl_.EnableVertexAttribArray(attribute);
    gl_.VertexAttribPointer(attribute, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                            reinterpret_cast<const void*>((attribute - 1) * 3 * sizeof(float)));
    gl_.VertexAttribDivisor(attribute, 1);
  }
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, occlusion_indices_);
  gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, sizeof faces, faces, GL_STATIC_DRAW);
  gl_.BindVertexArray(0);
  check_gl_error(gl_, "chunk_renderer: build_occlusion_program");
}

void ChunkRenderer::release_framebuffer() {
  if (framebuffer_) gl_.DeleteFramebuffers(1, &framebuffer_);
  const GLuint buffers[] = {color_buffer_, view_depth_buffer_, depth_buffer_, primitive_id_buffer_};
  for (GLuint b : buffers)
    if (b) gl_.DeleteRenderbuffers(1, &b);
  framebuffer_ = color_buffer_ = view_depth_buffer_ = depth_buffer_ = primitive_id_buffer_ = 0;
  frame_width_ = frame_height_ = 0;
}

void ChunkRenderer::resize_framebuffer(int width, int height) {
  release_framebuffer();
  gl_.GenFramebuffers(1, &framebuffer_);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  const auto make_buffer = [&](GLenum format, GLenum attachment) {
    GLuint rb = 0;
    gl_.GenRenderbuffers(1, &rb);
    gl_.BindRenderbuffer(GL_RENDERBUFFER, rb);
    gl_.RenderbufferStorage(GL_RENDERBUFFER, format, width, height);
    gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, rb);
    return rb;
  };
  color_buffer_ = make_buffer(GL_RGBA8, GL_COLOR_ATTACHMENT0);
  view_depth_buffer_ = make_buffer(GL_R32F, GL_COLOR_ATTACHMENT1);
  depth_buffer_ = make_buffer(GL_DEPTH_COMPONENT32F, GL_DEPTH_ATTACHMENT);
  check_framebuffer(width, height);
  frame_width_ = width;
  frame_height_ = height;
  check_gl_error(gl_, "chunk_renderer: resize_framebuffer");
}

void ChunkRenderer::check_framebuffer(int width, int height) {
  const GLenum status = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("chunk_renderer: framebuffer " + std::to_string(width) + "x" +
                             std::to_string(height) + " incomplete (status " + std::to_string(status) + ")");
}

void ChunkRenderer::add_primitive_id_buffer() {
  gl_.GenRenderbuffers(1, &primitive_id_buffer_);
  gl_.BindRenderbuffer(GL_RENDERBUFFER, primitive_id_buffer_);
  gl_.RenderbufferStorage(GL_RENDERBUFFER, GL_RG32UI, frame_width_, frame_height_);
  gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_RENDERBUFFER, primitive_id_buffer_);
  check_framebuffer(frame_width_, frame_height_);
  check_gl_error(gl_, "chunk_renderer: primitive-id attachment");
}

void ChunkRenderer::begin_frame(int width, int height, bool primitive_ids) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("chunk_renderer: frame size must be at least 1x1, got " + std::to_string(width) +
                                "x" + std::to_string(height));
  make_current();
  in_frame_ = false;
  if (width != frame_width_ || height != frame_height_ || !framebuffer_) resize_framebuffer(width, height);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  if (primitive_ids && !primitive_id_buffer_) add_primitive_id_buffer();
  if (primitive_ids && !programs_[1][0].id) build_program(true);
  primitive_ids_ = primitive_ids;
  frame_draws_.clear();
  const GLenum draw_buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  gl_.DrawBuffers(primitive_ids ? 3 : 2, draw_buffers);
  gl_.Viewport(0, 0, width, height);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthMask(GL_TRUE);
  gl_.Disable(GL_CULL_FACE);  // CAD models have inconsistent winding
  gl_.Disable(GL_BLEND);
  if (reversed_z()) {
    gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    gl_.DepthFunc(GL_GREATER);
  } else {
    gl_.DepthFunc(GL_LESS);
  }
  const float clear_color[4] = {0, 0, 0, 0};
  const float clear_view_depth[4] = {std::numeric_limits<float>::infinity(), 0, 0, 0};
  const float clear_depth = reversed_z() ? 0.0f : 1.0f;
  gl_.ClearBufferfv(GL_COLOR, 0, clear_color);
  gl_.ClearBufferfv(GL_COLOR, 1, clear_view_depth);
  gl_.ClearBufferfv(GL_DEPTH, 0, &clear_depth);
  if (primitive_ids) {
    const GLuint clear_ids[4] = {0, 0, 0, 0};
    gl_.ClearBufferuiv(GL_COLOR, 2, clear_ids);
  }
  check_gl_error(gl_, "chunk_renderer: begin_frame");
  in_frame_ = true;
}

void ChunkRenderer::require_frame(const char* what) const {
  if (!in_frame_) throw std::logic_error(std::string("chunk_renderer: ") + what + " called without begin_frame");
}

void ChunkRenderer::set_shading(const ShadingLights& lights) {
  const auto finite_unit = [](const Vec3d& v) { return is_finite(v) && std::abs(length(v) - 1) < 1e-6; };
  const auto strength = [](double s) { return s >= 0 && std::isfinite(s); };
  if (!finite_unit(lights.key) || !finite_unit(lights.fill) || !strength(lights.key_strength) ||
      !strength(lights.fill_strength) || !strength(lights.ambient))
    throw std::invalid_argument("chunk_renderer: shading needs unit light directions and finite strengths >= 0");
  lights_ = lights;
}

bool ChunkRenderer::is_cached(std::int64_t id) const { return cache_.contains(id); }

void ChunkRenderer::release(CachedChunk& entry) {
  gl_.DeleteVertexArrays(1, &entry.vertex_array);
  gl_.DeleteBuffers(1, &entry.vertex_buffer);
  gl_.DeleteBuffers(1, &entry.index_buffer);
  cached_bytes_ -= entry.bytes;
}

void ChunkRenderer::clear_cache() {
  make_current();
  for (auto& [id, entry] : cache_) release(entry);
  cache_.clear();
  lru_.clear();
}

void ChunkRenderer::evict_beyond_cap() {
  // Never evict the most recent entry: it is about to be drawn.
  while (cached_bytes_ > params_.cache_bytes && lru_.size() > 1) {
    const std::int64_t victim = lru_.back();
    lru_.pop_back();
    auto it = cache_.find(victim);
    release(it->second);
    cache_.erase(it);
    ++stats_.evictions;
  }
}

const ChunkRenderer::CachedChunk& ChunkRenderer::upload(const Chunk& chunk) {
  const std::string where = "chunk_renderer: chunk " + std::to_string(chunk.id);
  const std::size_t n = chunk.positions.size();
  if (!chunk.colors.empty() && chunk.colors.size() != n)
    throw std::runtime_error(where + " has " + std::to_string(chunk.colors.size()) + " colours for " +
                             std::to_string(n) + " positions");
  if (chunk.indices.size() % 3 != 0) throw std::runtime_error(where + " index count is not a multiple of 3");
  if (chunk.indices.size() > static_cast<std::size_t>(std::numeric_limits<GLsizei>::max()))
    throw std::runtime_error(where + " has too many indices");
  for (std::uint32_t i : chunk.indices)
    if (i >= n) throw std::runtime_error(where + " index " + std::to_string(i) + " out of range");

  if (!chunk.uvs.empty() && chunk.uvs.size() != n)
    throw std::runtime_error(where + " has " + std::to_string(chunk.uvs.size()) + " uvs for " + std::to_string(n) +
                             " positions");
  if (!chunk.normals.empty() && chunk.normals.size() != n)
    throw std::runtime_error(where + " has " + std::to_string(chunk.normals.size()) + " normals for " +
                             std::to_string(n) + " positions");
  if (!chunk.materials.empty() && chunk.materials.size() != chunk.indices.size() / 3)
    throw std::runtime_error(where + " has " + std::to_string(chunk.materials.size()) + " materials for " +
                             std::to_string(chunk.indices.size() / 3) + " triangles");
  const bool extended = !chunk.uvs.empty() || !chunk.normals.empty();
  std::vector<std::uint8_t> vertex_bytes(n * (extended ? sizeof(VertexExtended) : sizeof(Vertex)));
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f& p = chunk.positions[i];
    const Rgba8 color = chunk.colors.empty() ? Rgba8{} : chunk.colors[i];
    if (extended) {
      const Uv uv = chunk.uvs.empty() ? Uv{} : chunk.uvs[i];
      const VertexExtended v{p.x, p.y, p.z, color, uv.u, uv.v,
                             chunk.normals.empty() ? 0u : pack_normal_2_10_10_10(chunk.normals[i])};
      std::memcpy(vertex_bytes.data() + i * sizeof v, &v, sizeof v);
    } else {
      const Vertex v{p.x, p.y, p.z, color};
      std::memcpy(vertex_bytes.data() + i * sizeof v, &v, sizeof v);
    }
  }
  CachedChunk entry;
  std::vector<std::uint32_t> triangle_of;
  const std::vector<std::uint32_t> ordered = order_by_material(chunk, entry.ranges, triangle_of);
  if (!triangle_of.empty())
    entry.triangle_of = std::make_shared<const std::vector<std::uint32_t>>(std::move(triangle_of));
  entry.triangle_count = static_cast<std::uint32_t>(chunk.indices.size() / 3);
  const bool short_indices = n <= 65536;
  std::vector<std::uint16_t> indices16;
  if (short_indices) indices16.assign(ordered.begin(), ordered.end());
  const std::size_t index_bytes = ordered.size() * (short_indices ? 2 : 4);

  if (auto old = cache_.find(chunk.id); old != cache_.end()) {
    lru_.erase(old->second.recency);
    release(old->second);
    cache_.erase(old);
  }
  entry.origin = chunk.origin;
  entry.appearance = extended;
  entry.index_count = static_cast<int>(chunk.indices.size());
  entry.index_type = short_indices ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
  entry.bytes = vertex_bytes.size() + index_bytes;
  gl_.GenVertexArrays(1, &entry.vertex_array);
  gl_.BindVertexArray(entry.vertex_array);
  gl_.GenBuffers(1, &entry.vertex_buffer);
  gl_.BindBuffer(GL_ARRAY_BUFFER, entry.vertex_buffer);
  gl_.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertex_bytes.size()), vertex_bytes.data(), GL_STATIC_DRAW);
  const GLsizei stride = extended ? sizeof(VertexExtended) : sizeof(Vertex);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(0));
  gl_.EnableVertexAttribArray(1);
  gl_.VertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride,
                          reinterpret_cast<const void*>(offsetof(Vertex, color)));
  if (extended) {
    // Attributes left disabled read GL's default (0, 0, 0, 1): no uv, no normal.
    gl_.EnableVertexAttribArray(2);
    gl_.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride,
                            reinterpret_cast<const void*>(offsetof(VertexExtended, u)));
    if (!chunk.normals.empty()) {
      gl_.EnableVertexAttribArray(3);
      gl_.VertexAttribPointer(3, 4, GL_INT_2_10_10_10_REV, GL_TRUE, stride,
                              reinterpret_cast<const void*>(offsetof(VertexExtended, normal)));
    }
  }
  gl_.GenBuffers(1, &entry.index_buffer);
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, entry.index_buffer);
  gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(index_bytes),
                 short_indices ? static_cast<const void*>(indices16.data())
                               : static_cast<const void*>(ordered.data()),
                 GL_STATIC_DRAW);
  gl_.BindVertexArray(0);
  check_gl_error(gl_, where.c_str());

  lru_.push_front(chunk.id);
  entry.recency = lru_.begin();
  cached_bytes_ += entry.bytes;
  ++stats_.uploads;
  stats_.uploaded_bytes += entry.bytes;
  auto& stored = cache_[chunk.id] = entry;
  evict_beyond_cap();
  return stored;
}

void ChunkRenderer::set_camera_uniforms(const RenderCamera& camera, const Box3d& discard_box, BoxClip clip) {
  const std::array<float, 16> matrix = camera_view_projection(camera, reversed_z());
  const Vec3d key = lights_.key * lights_.key_strength, fill = lights_.fill * lights_.fill_strength;
  Vec3d lo{1, 1, 1}, hi{-1, -1, -1};  // an empty box: lo > hi on every axis, nothing strictly inside
  if (!discard_box.empty()) {
    lo = discard_box.lo - camera.eye;
    hi = discard_box.hi - camera.eye;
  }
  const auto put3 = [&](int location, const Vec3d& v) {
    gl_.Uniform3f(location, static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
  };
  for (int appearance = 1; appearance >= 0; --appearance) {
    const DrawProgram& p = program(appearance);
    gl_.UseProgram(p.id);
    gl_.UniformMatrix4fv(p.u_view_projection, 1, GL_FALSE, matrix.data());
    gl_.Uniform1i(p.u_keep_inside, clip == BoxClip::keep_inside ? 1 : 0);
    gl_.Uniform1i(p.u_lit, lights_.lit ? 1 : 0);
    put3(p.u_key, key);
    put3(p.u_fill, fill);
    gl_.Uniform1f(p.u_ambient, static_cast<float>(lights_.ambient));
    gl_.Uniform1i(p.u_texture, 0);
    gl_.Uniform1i(p.u_textured, 0);
    gl_.Uniform1i(p.u_alpha_test, 0);
    put3(p.u_forward, camera.forward);
    put3(p.u_discard_lo, lo);
    put3(p.u_discard_hi, hi);
  }
  active_program_ = 0;  // the loop ends on the plain program
  gl_.ActiveTexture(GL_TEXTURE0);
  textured_uniform_ = alpha_test_uniform_ = false;
  bound_texture_ = 0;
}

void ChunkRenderer::draw_cached(std::int64_t id, const CachedChunk& entry, const Vec3d& eye) {
  use_program(entry.appearance ? 1 : 0);
  const DrawProgram& p = program(active_program_);
  const Vec3d offset = entry.origin - eye;  // double, then float: eye-relative
  gl_.Uniform3f(p.u_offset, static_cast<float>(offset.x), static_cast<float>(offset.y),
                static_cast<float>(offset.z));
  if (primitive_ids_) {
    if (frame_draws_.size() >= static_cast<std::size_t>(std::numeric_limits<GLint>::max()))
      throw std::runtime_error("chunk_renderer: too many draws in one frame for primitive ids");
    frame_draws_.push_back({id, entry.triangle_count, entry.triangle_of});
    gl_.Uniform1i(p.u_draw, static_cast<GLint>(frame_draws_.size()));
  }
  if (entry.index_count > 0) {
    gl_.BindVertexArray(entry.vertex_array);
    const std::size_t index_size = entry.index_type == GL_UNSIGNED_SHORT ? 2 : 4;
    for (const ChunkDrawRange& range : entry.ranges) {
      if (entry.appearance) apply_material(range.material);
      if (primitive_ids_) gl_.Uniform1i(p.u_primitive_base, range.first / 3);
      gl_.DrawElements(GL_TRIANGLES, range.count, entry.index_type,
                       reinterpret_cast<const void*>(static_cast<std::uintptr_t>(range.first) * index_size));
    }
  }
  ++stats_.chunks_drawn;
  stats_.triangles_drawn += static_cast<std::uint64_t>(entry.index_count / 3);
}

void ChunkRenderer::apply_material(std::uint32_t index) {
  const Material* material = index < materials_.size() ? &materials_[index] : nullptr;
  const std::int64_t texture = material ? material->texture_id : 0;
  const bool alpha_test = texture > 0 && material->alpha_test;
  if (texture > 0 && texture != bound_texture_) {
    textures_->bind(texture, load_texture_);
    bound_texture_ = texture;
  }
  if ((texture > 0) != textured_uniform_) {
    textured_uniform_ = texture > 0;
    gl_.Uniform1i(program(1).u_textured, textured_uniform_ ? 1 : 0);
  }
  if (alpha_test != alpha_test_uniform_) {
    alpha_test_uniform_ = alpha_test;
    gl_.Uniform1i(program(1).u_alpha_test, alpha_test ? 1 : 0);
  }
}

void ChunkRenderer::set_materials(std::vector<Material> materials, TextureLoader load_texture) {
  make_current();
  materials_ = std::move(materials);
  load_texture_ = std::move(load_texture);
  textures_->clear();
  bound_texture_ = 0;
}

void ChunkRenderer::use_materials_of(const ChunkSource& source) {
  std::vector<Material> materials = source.materials();
  if (material_source_ == &source && materials == materials_) return;
  set_materials(std::move(materials), [&source](std::int64_t id) { return source.load_texture(id); });
  material_source_ = &source;
}

void ChunkRenderer::draw(const RenderCamera& camera, const Box3d& discard_box, std::span<const std::int64_t> ids,
                         const ChunkLoader& load, BoxClip clip) {
  require_frame("draw");
  make_current();
  set_camera_uniforms(camera, discard_box, clip);
  draw_ids(camera, ids, load);
}

void ChunkRenderer::draw_ids(const RenderCamera& camera, std::span<const std::int64_t> ids, const ChunkLoader& load) {
  for (std::int64_t id : ids) {
    auto it = cache_.find(id);
    if (it != cache_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.recency);
      draw_cached(id, it->second, camera.eye);
      continue;
    }
    const std::shared_ptr<const Chunk> chunk = load(id);
    if (!chunk) throw std::runtime_error("chunk_renderer: loader returned no chunk for id " + std::to_string(id));
    if (chunk->id != id)
      throw std::runtime_error("chunk_renderer: loader returned chunk " + std::to_string(chunk->id) + " for id " +
                               std::to_string(id));
    draw_cached(id, upload(*chunk), camera.eye);
  }
  gl_.BindVertexArray(0);
  check_gl_error(gl_, "chunk_renderer: draw");
}

std::size_t ChunkRenderer::upload_ahead(std::int64_t id, const ChunkLoader& load) {
  if (auto it = cache_.find(id); it != cache_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second.recency);
    return 0;
  }
  const std::shared_ptr<const Chunk> chunk = load(id);
  if (!chunk) throw std::runtime_error("chunk_renderer: loader returned no chunk for id " + std::to_string(id));
  if (chunk->id != id)
    throw std::runtime_error("chunk_renderer: loader returned chunk " + std::to_string(chunk->id) + " for id " +
                             std::to_string(id));
  make_current();
  const std::size_t bytes = upload(*chunk).bytes;
  gl_.BindVertexArray(0);
  return bytes;
}

void ChunkRenderer::test_boxes(const RenderCamera& camera, const std::vector<float>& boxes,
                               std::vector<std::uint32_t>& visible) {
  const std::size_t n = boxes.size() / 6;
  visible.assign(n, 0);
  if (n == 0) return;
  if (n > occlusion_capacity_) {
    occlusion_capacity_ = std::max(n, 2 * occlusion_capacity_);
    gl_.BindBuffer(GL_ARRAY_BUFFER, occlusion_boxes_);
    gl_.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(occlusion_capacity_ * 6 * sizeof(float)), nullptr,
                   GL_STREAM_DRAW);
    gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, occlusion_flags_);
    gl_.BufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(occlusion_capacity_ * sizeof(std::uint32_t)),
                   nullptr, GL_STREAM_READ);
  }
  gl_.BindBuffer(GL_ARRAY_BUFFER, occlusion_boxes_);
  gl_.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(boxes.size() * sizeof(float)), boxes.data());
  gl_.BindBuffer(GL_SHADER_STORAGE_BUFFER, occlusion_flags_);
  gl_.BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(n * sizeof(std::uint32_t)), visible.data());
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, occlusion_flags_);

  const std::array<float, 16> matrix = camera_view_projection(camera, reversed_z());
  gl_.UseProgram(occlusion_program_);
  gl_.UniformMatrix4fv(u_occlusion_view_projection_, 1, GL_FALSE, matrix.data());
  gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  gl_.DepthMask(GL_FALSE);
  gl_.BindVertexArray(occlusion_vertex_array_);
  gl_.DrawElementsInstanced(GL_TRIANGLES, 36, GL_UNSIGNED_BYTE, nullptr, static_cast<GLsizei>(n));
  gl_.BindVertexArray(0);
  gl_.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  gl_.Finish();
  gl_.GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(n * sizeof(std::uint32_t)),
                       visible.data());
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.DepthMask(GL_TRUE);
  gl_.UseProgram(program(active_program_).id);
  stats_.occlusion_tests += n;
  check_gl_error(gl_, "chunk_renderer: occlusion test");
}

void ChunkRenderer::draw_unoccluded(const RenderCamera& camera, const Box3d& discard_box,
                                    std::span<const ChunkRef> chunks, const ChunkLoader& load,
                                    std::vector<std::int64_t>* drawn) {
  require_frame("draw_unoccluded");
  make_current();
  set_camera_uniforms(camera, discard_box, BoxClip::discard_inside);
  std::vector<std::int64_t> ids;
  ids.reserve(chunks.size());
  if (!occlusion_culling()) {
    for (const ChunkRef& c : chunks) ids.push_back(c.id);
    draw_ids(camera, ids, load);
    if (drawn) drawn->insert(drawn->end(), ids.begin(), ids.end());
    check_gl_error(gl_, "chunk_renderer: draw_unoccluded");
    return;
  }
  std::vector<ChunkRef> pending(chunks.begin(), chunks.end());
  std::vector<ChunkRef> kept, tested;
  std::vector<float> boxes;
  std::vector<std::uint32_t> visible;
  std::size_t batch = kFirstUntestedBatch;
  while (!pending.empty()) {
    const std::size_t count = std::min(batch, pending.size());
    ids.clear();
    for (std::size_t i = 0; i < count; ++i) ids.push_back(pending[i].id);
    draw_ids(camera, ids, load);
    if (drawn) drawn->insert(drawn->end(), ids.begin(), ids.end());
    pending.erase(pending.begin(), pending.begin() + static_cast<std::ptrdiff_t>(count));
    batch *= 2;
    if (pending.empty()) break;

    // Boxes relative to the eye, enlarged by a margin ~1000x float rounding of
    // their coordinates so that rounding in rasterising box and chunk alike
    // cannot put a chunk fragment in front of its box.
    kept.clear();
    tested.clear();
    boxes.clear();
    for (const ChunkRef& c : pending) {
      Vec3d lo = c.bounds.lo - camera.eye, hi = c.bounds.hi - camera.eye;
      double scale = 0;
      for (int k = 0; k < 3; ++k) scale = std::max({scale, std::abs(lo[k]), std::abs(hi[k])});
      const double margin = 1e-4 * scale + 1e-6;
      lo = lo - Vec3d{margin, margin, margin};
      hi = hi + Vec3d{margin, margin, margin};
      double nearest = 0;  // smallest forward distance over the box
      for (int k = 0; k < 3; ++k) nearest += camera.forward[k] * (camera.forward[k] >= 0 ? lo[k] : hi[k]);
      if (nearest <= 2 * camera.near_plane) {
        kept.push_back(c);  // the near plane would clip the box open: never cull
        continue;
      }
      tested.push_back(c);
      for (const Vec3d& p : {lo, hi})
        for (int k = 0; k < 3; ++k) boxes.push_back(static_cast<float>(p[k]));
    }
    if (tested.empty()) continue;
    test_boxes(camera, boxes, visible);
    // Keep the draw order: merge the untested and visible chunks back by position.
    std::vector<ChunkRef> next;
    next.reserve(pending.size());
    std::size_t ti = 0, ki = 0;
    for (const ChunkRef& c : pending) {
      if (ki < kept.size() && kept[ki].id == c.id) {
        next.push_back(c);
        ++ki;
      } else if (visible[ti++]) {
        next.push_back(c);
      } else {
        ++stats_.chunks_occluded;
      }
    }
    pending = std::move(next);
  }
  gl_.BindVertexArray(0);
  check_gl_error(gl_, "chunk_renderer: draw_unoccluded");
}

void ChunkRenderer::draw(const RenderCamera& camera, const Box3d& discard_box,
                         std::span<const std::shared_ptr<const Chunk>> chunks, BoxClip clip) {
  std::vector<std::int64_t> ids;
  std::unordered_map<std::int64_t, const std::shared_ptr<const Chunk>*> by_id;
  ids.reserve(chunks.size());
  for (const auto& c : chunks) {
    if (!c) throw std::invalid_argument("chunk_renderer: null chunk in draw list");
    ids.push_back(c->id);
    by_id[c->id] = &c;
  }
  draw(camera, discard_box, ids, [&](std::int64_t id) { return *by_id.at(id); }, clip);
}

void ChunkRenderer::read_frame(std::vector<Rgba8>& color, std::vector<float>& depth) {
  require_frame("read_frame");
  make_current();
  const std::size_t w = static_cast<std::size_t>(frame_width_), h = static_cast<std::size_t>(frame_height_);
  readback_color_.resize(w * h);
  readback_depth_.resize(w * h);
  gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer_);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
  gl_.ReadPixels(0, 0, frame_width_, frame_height_, GL_RGBA, GL_UNSIGNED_BYTE, readback_color_.data());
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT1);
  gl_.ReadPixels(0, 0, frame_width_, frame_height_, GL_RED, GL_FLOAT, readback_depth_.data());
  check_gl_error(gl_, "chunk_renderer: read_frame");
  // GL's row 0 is the bottom; ours is the top.
  color.resize(w * h);
  depth.resize(w * h);
  for (std::size_t row = 0; row < h; ++row) {
    const std::size_t src = (h - 1 - row) * w;
    std::memcpy(color.data() + row * w, readback_color_.data() + src, w * sizeof(Rgba8));
    std::memcpy(depth.data() + row * w, readback_depth_.data() + src, w * sizeof(float));
  }
}

void ChunkRenderer::read_primitive_ids(std::vector<std::int64_t>& chunk,
                                       std::vector<std::uint32_t>& triangle) {
  require_frame("read_primitive_ids");
  if (!primitive_ids_)
    throw std::logic_error("chunk_renderer: read_primitive_ids on a frame begun without primitive ids");
  make_current();
  const std::size_t w = static_cast<std::size_t>(frame_width_), h = static_cast<std::size_t>(frame_height_);
  readback_ids_.resize(2 * w * h);
  gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer_);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT2);
  gl_.ReadPixels(0, 0, frame_width_, frame_height_, GL_RG_INTEGER, GL_UNSIGNED_INT, readback_ids_.data());
  check_gl_error(gl_, "chunk_renderer: read_primitive_ids");
  chunk.resize(w * h);
  triangle.resize(w * h);
  // GL's row 0 is the bottom; ours is the top. Neighbouring pixels mostly
  // share a draw, so its entry is looked up once per run.
  std::uint32_t last = 0;
  const FrameDraw* draw = nullptr;
  for (std::size_t row = 0; row < h; ++row) {
    const std::uint32_t* src = readback_ids_.data() + 2 * (h - 1 - row) * w;
    std::int64_t* chunk_row = chunk.data() + row * w;
    std::uint32_t* triangle_row = triangle.data() + row * w;
    for (std::size_t col = 0; col < w; ++col) {
      const std::uint32_t number = src[2 * col], drawn = src[2 * col + 1];
      if (number == 0) {
        chunk_row[col] = -1;
        triangle_row[col] = 0;
        continue;
      }
      if (number != last) {
        if (number > frame_draws_.size())
          throw std::runtime_error("chunk_renderer: primitive-id attachment names draw " +
                                   std::to_string(number) + " of " + std::to_string(frame_draws_.size()));
        draw = &frame_draws_[number - 1];
        last = number;
      }
      if (drawn >= draw->triangle_count)
        throw std::runtime_error("chunk_renderer: primitive-id attachment names triangle " +
                                 std::to_string(drawn) + " of chunk " + std::to_string(draw->id) +
                                 ", which has " + std::to_string(draw->triangle_count));
      chunk_row[col] = draw->id;
      triangle_row[col] = draw->triangle_of ? (*draw->triangle_of)[drawn] : drawn;
    }
  }
}

bool ChunkRenderer::reversed_z() const { return gl_.ClipControl != nullptr; }

ChunkRendererStats ChunkRenderer::stats() const {
  ChunkRendererStats s = stats_;
  s.texture_uploads = textures_->uploads();
  s.cached_textures = textures_->size();
  s.cached_texture_bytes = textures_->bytes();
  s.cached_chunks = cache_.size();
  s.cached_bytes = cached_bytes_;
  return s;
}

}  // namespace cellbake
