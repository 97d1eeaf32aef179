// Textured depth meshes (Wilson 2002, ch. 4–5) drawn beside a ChunkRenderer's
// chunks: positions relative to their sample's eye are moved to camera-relative
// coordinates by one double-precision offset per mesh (as chunks are), the
// fragment shader writes the texture colour and the exact planar view depth.
#include "viewer/tdm_renderer.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/render/gl_functions.h"

namespace cellbake {
namespace {

// Texture coordinates are projective (the face image is projected from the
// sample's eye onto the mesh, Segal et al. 1992): a vertex carries (u q, v q, q)
// with q its planar depth in its cube face's frame, the rasteriser interpolates
// them linearly over the triangle in 3D (perspective-correct), and the fragment
// divides. That gives every point of a triangle the texel on the sample ray
// through it, as the cube-face camera saw it. Plain (u, v) interpolated
// perspective-correctly would instead be linear in 3D over the triangle, which
// differs from the projection wherever a triangle's corners lie at different
// depths from the sample eye: nothing in a dense one-pixel mesh, but pixels to
// tens of pixels inside the large triangles the simplifier leaves on slanted
// planes, so textures slid about under their geometry even at the sample point.
constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;  // relative to the sample's eye
layout(location = 1) in vec3 a_uvq;       // (u q, v q, q), q = planar depth in the face's frame
uniform vec3 u_offset;                    // sample eye - camera eye, world axes
uniform mat4 u_view_projection;
uniform vec3 u_forward;
out vec3 v_uvq;
out float v_view_depth;
void main() {
  vec3 relative = a_position + u_offset;
  v_uvq = a_uvq;
  v_view_depth = dot(relative, u_forward);
  gl_Position = u_view_projection * vec4(relative, 1.0);
}
)";

constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 v_uvq;
in float v_view_depth;
uniform sampler2D u_image;
uniform vec4 u_tint;
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_view_depth;
void main() {
  vec4 c = textureProj(u_image, v_uvq);  // texture at v_uvq.xy / v_uvq.z
  o_color = vec4(mix(c.rgb, u_tint.rgb, u_tint.a), 1.0);
  o_view_depth = v_view_depth;
}
)";

struct Vertex {
  float x, y, z;
  float uq, vq, q;  // projective texture coordinates (see kVertexShader)
};

// The direction (forward component 1) of face b's sample ray through texture
// coordinates (u, v): face coordinates s = 2 u - 1, t = 1 - 2 v (stages/cube_map.h).
Vec3d face_direction(const FaceBasis& b, const Uv& uv) {
  return cube_face_direction(b, 2.0 * uv.u - 1.0, 1.0 - 2.0 * uv.v);
}

Vec3d to_double(const Vec3f& p) { return {p.x, p.y, p.z}; }

// The cube face (0..5) whose sample rays through the vertices' texture
// coordinates pass closest to the vertices: every vertex in front of the face
// and, for the face chosen, the largest distance of a vertex off its ray,
// relative to the vertex's distance from the eye, below 1/4 and smallest over
// the faces. -1 when no face fits (not a face mesh of build_depth_meshes).
// Any other face misses most vertices by far more than 1/4: the right face
// misses them only by the encoder's quantisation.
int fitted_cube_face(const FaceMesh& mesh) {
  int best = -1;
  double best_miss = 0.25;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis b = cube_face_basis(f);
    double worst = 0;
    for (std::size_t i = 0; i < mesh.positions.size() && worst < best_miss; ++i) {
      const Vec3d p = to_double(mesh.positions[i]);
      const double z = dot(p, b.forward);
      worst = z > 0 ? std::max(worst, length(p - face_direction(b, mesh.uvs[i]) * z) / length(p))
                    : std::numeric_limits<double>::infinity();
    }
    if (worst < best_miss) best = f, best_miss = worst;
  }
  return best;
}

// The planar depth of a face-mesh vertex in its face's frame when the face is
// unknown: the vertex is at q (forward + s right + t up), so q is its distance
// over |(1, s, t)|.
double planar_depth(const Vec3d& p, const Uv& uv) {
  const double s = 2.0 * uv.u - 1.0, t = 1.0 - 2.0 * uv.v;
  return length(p) / std::sqrt(1.0 + s * s + t * t);
}

std::unique_ptr<GlFunctions> load_for(GlContext* context) {
  if (!context) throw std::invalid_argument("tdm_renderer: null GL context");
  context->make_current();
  return std::make_unique<GlFunctions>(load_gl_functions(*context));
}

}  // namespace

TdmRenderer::TdmRenderer(std::shared_ptr<GlContext> context)
    : context_(std::move(context)), gl_(load_for(context_.get())) {
  const GlFunctions& gl = *gl_;
  program_ = build_gl_program(gl, kVertexShader, kFragmentShader, "tdm_renderer");
  u_offset_ = gl.GetUniformLocation(program_, "u_offset");
  u_view_projection_ = gl.GetUniformLocation(program_, "u_view_projection");
  u_forward_ = gl.GetUniformLocation(program_, "u_forward");
  u_image_ = gl.GetUniformLocation(program_, "u_image");
  u_tint_ = gl.GetUniformLocation(program_, "u_tint");
  check_gl_error(gl, "tdm_renderer: build program");
}

TdmRenderer::~TdmRenderer() {
  try {
    context_->make_current();
    for (auto& [handle, u] : uploads_) free(u);
    if (program_) gl_->DeleteProgram(program_);
  } catch (...) {
    // The context goes away with its last handle; its objects go with it.
  }
}

void TdmRenderer::free(Upload& u) {
  gl_->DeleteVertexArrays(1, &u.vertex_array);
  gl_->DeleteBuffers(1, &u.vertex_buffer);
  gl_->DeleteBuffers(1, &u.index_buffer);
  gl_->DeleteTextures(1, &u.texture);
  bytes_ -= u.bytes;
}

std::uint64_t TdmRenderer::upload(const FaceMesh& mesh, const DecodedImage& image, const Vec3d& sample_eye) {
  const std::size_t n = mesh.positions.size();
  if (image.width < 1 || image.height < 1 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height))
    throw std::invalid_argument("tdm_renderer: face image is empty or mis-sized");
  if (mesh.uvs.size() != n) throw std::invalid_argument("tdm_renderer: face mesh uvs are not one per position");
  if (mesh.indices.size() % 3 != 0) throw std::runtime_error("tdm_renderer: index count is not a multiple of 3");
  for (std::uint32_t i : mesh.indices)
    if (i >= n) throw std::runtime_error("tdm_renderer: index " + std::to_string(i) + " out of range");
  // Every vertex of a face mesh lies on the sample ray through its texture
  // coordinates (a pixel corner), and where two surfaces meet on a silhouette
  // both sides have a vertex on the same corner ray, so that the outline they
  // share is one line seen from the sample eye. encode_face_mesh quantises
  // positions per axis over the mesh's bounds, which moves each vertex off its
  // ray by up to half a step, independently for the two depths of a
  // silhouette corner: the shared outline opened into cracks showing the
  // background (black) and slivers of overlap along every far-field edge, even
  // at the sample point (0.05 px at 5 m for a 60 m model at 16 bits, whole
  // pixels for kilometre-scale models or fewer bits), and likewise along cube
  // edges. The ray is known exactly from the texture coordinates, so vertices
  // found off it are put back on it at their planar depth (which is all the
  // quantisation leaves of them). Vertices already on their ray to float
  // rounding (meshes that were not encoded) are kept bit for bit, which keeps
  // the faces' shared border vertices identical.
  const int face = fitted_cube_face(mesh);
  const FaceBasis basis = cube_face_basis(std::max(face, 0));
  std::vector<Vertex> vertices(n);
  for (std::size_t i = 0; i < n; ++i) {
    Vec3f p = mesh.positions[i];
    const Uv& uv = mesh.uvs[i];
    double q;
    if (face >= 0) {
      const Vec3d position = to_double(p), direction = face_direction(basis, uv);
      q = dot(position, basis.forward);
      const Vec3d on_ray = direction * q;
      if (length(position - on_ray) > 1e-6 * length(position))
        p = {static_cast<float>(on_ray.x), static_cast<float>(on_ray.y), static_cast<float>(on_ray.z)};
    } else {
      q = planar_depth(to_double(p), uv);
    }
    // A vertex at the sample eye itself (never made by build_depth_meshes)
    // would divide by zero: keep q positive.
    const float qf = q > 1e-20 ? static_cast<float>(q) : 1e-20f;
    vertices[i] = {p.x, p.y, p.z, uv.u * qf, uv.v * qf, qf};
  }

  context_->make_current();
  const GlFunctions& gl = *gl_;
  Upload u;
  u.eye = sample_eye;
  u.index_count = static_cast<int>(mesh.indices.size());
  u.bytes = vertices.size() * sizeof(Vertex) + mesh.indices.size() * 4 + image.pixels.size() * 4;
  gl.GenVertexArrays(1, &u.vertex_array);
  gl.BindVertexArray(u.vertex_array);
  gl.GenBuffers(1, &u.vertex_buffer);
  gl.BindBuffer(GL_ARRAY_BUFFER, u.vertex_buffer);
  gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)), vertices.data(),
                GL_STATIC_DRAW);
  gl.EnableVertexAttribArray(0);
  gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<const void*>(0));
  gl.EnableVertexAttribArray(1);
  gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, uq)));
  gl.GenBuffers(1, &u.index_buffer);
  gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, u.index_buffer);
  gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.indices.size() * 4), mesh.indices.data(),
                GL_STATIC_DRAW);
  gl.BindVertexArray(0);
  // Row 0 of the image (the top, v = 0) becomes texture row t = 0, so v maps to t unchanged.
  gl.GenTextures(1, &u.texture);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, u.texture);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                image.pixels.data());
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  try {
    check_gl_error(gl, "tdm_renderer: upload");
  } catch (...) {
    free(u);
    throw;
  }
  const std::uint64_t handle = next_handle_++;
  uploads_[handle] = u;
  bytes_ += u.bytes;
  uploaded_bytes_ += u.bytes;
  return handle;
}

void TdmRenderer::erase(std::uint64_t handle) {
  auto it = uploads_.find(handle);
  if (it == uploads_.end()) return;
  context_->make_current();
  free(it->second);
  uploads_.erase(it);
}

std::uint64_t TdmRenderer::draw(const RenderCamera& camera, bool reversed_z, std::span<const std::uint64_t> handles,
                                const TdmDrawOptions& options) {
  std::vector<Range> ranges;
  ranges.reserve(handles.size());
  for (std::uint64_t handle : handles) {
    auto it = uploads_.find(handle);
    if (it == uploads_.end()) throw std::out_of_range("tdm_renderer: unknown upload handle " + std::to_string(handle));
    ranges.push_back({handle, 0, static_cast<std::uint32_t>(it->second.index_count)});
  }
  return draw_ranges(camera, reversed_z, ranges, options);
}

std::uint64_t TdmRenderer::draw_ranges(const RenderCamera& camera, bool reversed_z, std::span<const Range> ranges,
                                       const TdmDrawOptions& options) {
  for (const Range& r : ranges) {
    auto it = uploads_.find(r.handle);
    if (it == uploads_.end()) throw std::out_of_range("tdm_renderer: unknown upload handle " + std::to_string(r.handle));
    if (std::uint64_t(r.first_index) + r.index_count > std::uint64_t(it->second.index_count))
      throw std::out_of_range("tdm_renderer: index range past upload " + std::to_string(r.handle));
  }
  const std::array<float, 16> matrix = camera_view_projection(camera, reversed_z);
  context_->make_current();
  const GlFunctions& gl = *gl_;
  gl.UseProgram(program_);
  gl.UniformMatrix4fv(u_view_projection_, 1, GL_FALSE, matrix.data());
  gl.Uniform3f(u_forward_, static_cast<float>(camera.forward.x), static_cast<float>(camera.forward.y),
               static_cast<float>(camera.forward.z));
  gl.Uniform4f(u_tint_, options.tint[0], options.tint[1], options.tint[2], options.tint[3]);
  gl.Uniform1i(u_image_, 0);
  gl.ActiveTexture(GL_TEXTURE0);
  if (options.wireframe) gl.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  std::uint64_t triangles = 0;
  std::uint64_t bound = 0;
  for (const Range& r : ranges) {
    const Upload& u = uploads_.at(r.handle);
    if (r.handle != bound) {
      const Vec3d offset = u.eye - camera.eye;  // double, then float: camera-relative
      gl.Uniform3f(u_offset_, static_cast<float>(offset.x), static_cast<float>(offset.y), static_cast<float>(offset.z));
      gl.BindTexture(GL_TEXTURE_2D, u.texture);
      gl.BindVertexArray(u.vertex_array);
      bound = r.handle;
    }
    if (r.index_count > 0)
      gl.DrawElements(GL_TRIANGLES, static_cast<int>(r.index_count), GL_UNSIGNED_INT,
                      reinterpret_cast<const void*>(std::uintptr_t(r.first_index) * sizeof(std::uint32_t)));
    triangles += r.index_count / 3;
  }
  if (options.wireframe) gl.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  gl.BindVertexArray(0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  check_gl_error(gl, "tdm_renderer: draw");
  return triangles;
}

}  // namespace cellbake
