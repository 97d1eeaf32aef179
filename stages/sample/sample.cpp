// Panoramic sampling of the far field, Wilson 2002 ch. 3 and §7.3.1.3: six
// 90-degree cube faces of colour + planar depth per sample point, drawing only
// geometry outside the cell's cull box (per-fragment discard, since the region
// outside a box seen from an off-centre eye is not a convex clip volume), with
// per-face frustum culling of chunks so that only visible chunks are loaded.
#include "stages/sample/sample.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>


namespace cellbake {
namespace {

constexpr int kMaxRenderSize = 16384;  // pixels per edge, GL renderbuffer limits are of this order

// Largest value of dot(n, p) over the box (p relative to the eye).
double max_dot(const Vec3d& n, const Vec3d& lo, const Vec3d& hi) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += n[k] * (n[k] >= 0 ? hi[k] : lo[k]);
  return s;
}

}  // namespace

void validate_sample_inputs(const Vec3d& eye, const SampleParams& p) {
  if (!is_finite(eye)) throw std::invalid_argument("sample: eye is not finite");
  if (p.face_size < 1) throw std::invalid_argument("sample: face_size must be >= 1, got " + std::to_string(p.face_size));
  if (p.supersample < 1)
    throw std::invalid_argument("sample: supersample must be >= 1, got " + std::to_string(p.supersample));
  if (static_cast<long long>(p.face_size) * p.supersample > kMaxRenderSize)
    throw std::invalid_argument("sample: face_size * supersample exceeds " + std::to_string(kMaxRenderSize));
  if (!(p.near_plane > 0) || !std::isfinite(p.near_plane))
    throw std::invalid_argument("sample: near_plane must be positive, got " + std::to_string(p.near_plane));
  if (!(p.depth_agreement >= 0))
    throw std::invalid_argument("sample: depth_agreement must be >= 0, got " + std::to_string(p.depth_agreement));
}

std::vector<ChunkRef> chunks_in_face(int face, const Vec3d& eye, const Box3d& cull_box, double near_plane,
                                     const ChunkSource& source) {
  if (face < 0 || face >= kCubeFaces) throw std::invalid_argument("sample: face " + std::to_string(face) + " out of range");
  const Box3d model = source.model_bounds();
  if (model.empty()) return {};
  const FaceBasis b = cube_face_basis(face);

  // How far along `forward` the model reaches; the frustum needs to go no further.
  double reach = -std::numeric_limits<double>::infinity();
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d p{corner & 1 ? model.hi.x : model.lo.x, corner & 2 ? model.hi.y : model.lo.y,
                  corner & 4 ? model.hi.z : model.lo.z};
    reach = std::max(reach, dot(p - eye, b.forward));
  }
  if (reach < near_plane) return {};

  Box3d frustum_box;
  for (double d : {near_plane, reach})
    for (double s : {-1.0, 1.0})
      for (double t : {-1.0, 1.0}) frustum_box.expand(eye + cube_face_direction(b, s, t) * d);

  // Inward normals of the side planes through the eye: |s| <= 1 and |t| <= 1.
  const std::array<Vec3d, 4> sides = {b.forward - b.right, b.forward + b.right, b.forward - b.up, b.forward + b.up};
  std::vector<ChunkRef> result;
  for (const ChunkRef& ref : source.query(frustum_box)) {
    if (ref.bounds.empty() || cull_box.strictly_contains(ref.bounds)) continue;
    const Vec3d lo = ref.bounds.lo - eye, hi = ref.bounds.hi - eye;
    if (max_dot(b.forward, lo, hi) < near_plane) continue;
    bool outside = false;
    for (const Vec3d& n : sides) outside = outside || max_dot(n, lo, hi) < 0;
    if (!outside) result.push_back(ref);
  }
  std::sort(result.begin(), result.end(), [](const ChunkRef& a, const ChunkRef& c) { return a.id < c.id; });
  return result;
}

CubeFace finish_face(std::vector<Rgba8>& color, std::vector<float>& depth, const SampleParams& params) {
  if (params.supersample != 1)
    return downsample_face(color, depth, params.face_size, params.supersample, params.depth_agreement);
  CubeFace out;
  out.size = params.face_size;
  out.color = std::move(color);
  out.depth = std::move(depth);
  color.clear();
  depth.clear();
  return out;
}

CubeFace downsample_face(const std::vector<Rgba8>& color, const std::vector<float>& depth, int size, int factor,
                         double depth_agreement) {
  const std::size_t big = static_cast<std::size_t>(size) * factor;
  if (size < 1 || factor < 1 || color.size() != big * big || depth.size() != big * big)
    throw std::invalid_argument("sample: downsample_face input is not (size * factor)^2 pixels");
  CubeFace out;
  out.size = size;
  out.color.assign(static_cast<std::size_t>(size) * size, Rgba8{0, 0, 0, 0});
  out.depth.assign(static_cast<std::size_t>(size) * size, kBackgroundDepth);
  const int block = factor * factor;
  for (int row = 0; row < size; ++row) {
    for (int col = 0; col < size; ++col) {
      int covered = 0;
      unsigned sum[4] = {0, 0, 0, 0};
      double min_d = std::numeric_limits<double>::infinity(), max_d = 0, inverse_sum = 0;
      for (int dy = 0; dy < factor; ++dy) {
        const std::size_t base = (static_cast<std::size_t>(row) * factor + dy) * big + static_cast<std::size_t>(col) * factor;
        for (int dx = 0; dx < factor; ++dx) {
          const float d = depth[base + dx];
          if (!std::isfinite(d)) continue;
          const Rgba8 c = color[base + dx];
          sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, sum[3] += c.a;
          min_d = std::min(min_d, static_cast<double>(d));
          max_d = std::max(max_d, static_cast<double>(d));
          inverse_sum += 1.0 / d;
          ++covered;
        }
      }
      if (covered == 0) continue;
      const std::size_t i = static_cast<std::size_t>(row) * size + col;
      const auto average = [&](unsigned s) { return static_cast<std::uint8_t>((s + covered / 2) / covered); };
      out.color[i] = {average(sum[0]), average(sum[1]), average(sum[2]), average(sum[3])};
      const bool one_surface = covered == block && max_d <= min_d * (1 + depth_agreement);
      out.depth[i] = static_cast<float>(one_surface ? block / inverse_sum : min_d);
    }
  }
  return out;
}

std::vector<ChunkRef> chunks_in_face_nearest_first(int face, const Vec3d& eye, const Box3d& cull_box,
                                                   double near_plane, const ChunkSource& source) {
  const FaceBasis b = cube_face_basis(face);
  std::vector<ChunkRef> refs = chunks_in_face(face, eye, cull_box, near_plane, source);
  std::vector<std::pair<double, std::size_t>> order(refs.size());
  for (std::size_t i = 0; i < refs.size(); ++i)
    order[i] = {max_dot(b.forward * -1.0, refs[i].bounds.lo - eye, refs[i].bounds.hi - eye) * -1.0, i};
  std::sort(order.begin(), order.end());  // refs are sorted by id, so ties keep id order
  std::vector<ChunkRef> nearest_first;
  nearest_first.reserve(refs.size());
  for (const auto& [distance, i] : order) nearest_first.push_back(refs[i]);
  return nearest_first;
}

}  // namespace cellbake
