// One cube face's rays against one instance scene (see face_tracer.h). Embree 3:
// Wald et al. 2014, "Embree: a kernel framework for efficient CPU ray tracing",
// ACM TOG 33(4); coherent streams: Fuetterling et al. 2015, JCGT 4(5);
// https://www.embree.org/api.html.
#include "stages/raycast/face_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "stages/raycast/embree_cube_sampler.h"

namespace cellbake {
namespace {

constexpr unsigned kStream = 1024;  // rays per rtcIntersect1M call
// How many hits ahead shading asks for a triangle's indices, and for its
// corners' attributes (prefetch_triangle_indices, prefetch_corner_attributes).
constexpr unsigned kPrefetchIndicesAhead = 32;
constexpr unsigned kPrefetchAttributesAhead = 16;
// Alpha-tested layers a ray passes through before it gives up (background).
constexpr int kMaxAlphaLayers = 64;

void init_ray(RTCRayHit& r, const Vec3f& origin, const Vec3d& dir, float tnear, float tfar, unsigned id) {
  r.ray.org_x = origin.x;
  r.ray.org_y = origin.y;
  r.ray.org_z = origin.z;
  r.ray.dir_x = static_cast<float>(dir.x);
  r.ray.dir_y = static_cast<float>(dir.y);
  r.ray.dir_z = static_cast<float>(dir.z);
  r.ray.tnear = tnear;
  r.ray.tfar = tfar;
  r.ray.time = 0;
  r.ray.mask = 0xFFFFFFFFu;
  r.ray.id = id;
  r.ray.flags = 0;
  r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  r.hit.primID = RTC_INVALID_GEOMETRY_ID;
  r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

// The chunk a ray hit in `scene` (null: a miss).
const Chunk* hit_chunk(const InstanceScene& scene, const RTCRayHit& r) {
  if (r.hit.geomID == RTC_INVALID_GEOMETRY_ID) return nullptr;
  return scene.instance(r.hit.instID[0]).chunks[r.hit.geomID].get();
}

// The chunk triangle and barycentrics of a ray's hit in `scene`.
SurfaceHit surface_hit(const InstanceScene& scene, const RTCRayHit& r) {
  SurfaceHit hit;
  hit.chunk = hit_chunk(scene, r);
  hit.triangle = r.hit.primID;
  hit.u = r.hit.u;
  hit.v = r.hit.v;
  hit.geometric_normal = {r.hit.Ng_x, r.hit.Ng_y, r.hit.Ng_z};  // instances only translate
  return hit;
}

}  // namespace

void FaceHits::clear(std::size_t pixels) {
  color.assign(pixels, Rgba8{0, 0, 0, 0});
  depth.assign(pixels, kBackgroundDepth);
  chunk.assign(pixels, -1);
  triangle.assign(pixels, 0);
}

FaceTracer::FaceTracer(const HitShader& shader, const HitTexturer& texturer, const EyeBox& box, double near_plane,
                       int size, std::span<const std::uint32_t> order, std::span<const double> coordinate,
                       std::span<const double> inverse_coordinate, FaceSlabs& slabs, EmbreeSamplerStats& stats,
                       bool colour)
    : shader_(shader),
      texturer_(texturer),
      box_(box),
      near_plane_(near_plane),
      colour_(colour),
      size_(size),
      pixels_(std::size_t(size) * std::size_t(size)),
      order_(order),
      coordinate_(coordinate),
      inverse_coordinate_(inverse_coordinate),
      slabs_(slabs),
      stats_(stats),
      rays_(kStream),
      again_(kStream),
      second_(kStream) {
  rtcInitIntersectContext(&context_);
  context_.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
}

void FaceTracer::trace(const InstanceScene& scene, int face, FaceHits& out) {
  scene_ = &scene;
  out_ = &out;
  basis_ = cube_face_basis(face);
  const auto to_float = [](const Vec3d& v) { return Vec3f{float(v.x), float(v.y), float(v.z)}; };
  step_x_ = to_float(basis_.right * (2.0 / size_)), step_y_ = to_float(basis_.up * (2.0 / size_));
  slabs_.set(basis_, box_, coordinate_, inverse_coordinate_);
  for (std::size_t start = 0; start < pixels_; start += kStream) {
    const unsigned count = unsigned(std::min<std::size_t>(kStream, pixels_ - start));
    set_up_rays(start, count);
    rtcIntersect1M(scene.scene(), &context_, rays_.data(), count, sizeof(RTCRayHit));
    stats_.rays += count;
    trace_second_segments(start, count);
    shade_hits(start, count);
  }
}

void FaceTracer::set_up_rays(std::size_t start, unsigned count) {
  const std::vector<float>& depth = out_->depth;
  for (unsigned k = 0; k < count; ++k) {
    const std::uint32_t p = order_[start + k];
    const std::uint32_t row = p / std::uint32_t(size_), col = p - row * std::uint32_t(size_);
    const Vec3d dir = cube_face_direction(basis_, coordinate_[col], -coordinate_[row]);
    const RaySegments seg = slabs_.segments(col, row, near_plane_);
    init_ray(rays_[k], scene_->ray_origin(), dir, seg.t0, std::min(seg.t1, depth[p]), p);
    second_[k] = seg.two && seg.t2 < depth[p] ? seg.t2 : std::numeric_limits<float>::infinity();
  }
}

void FaceTracer::trace_second_segments(std::size_t start, unsigned count) {
  unsigned missed = 0;
  for (unsigned k = 0; k < count; ++k) {
    if (rays_[k].hit.geomID != RTC_INVALID_GEOMETRY_ID || std::isinf(second_[k])) continue;
    RTCRayHit& r = again_[missed++];
    r = rays_[k];
    r.ray.tnear = second_[k];
    r.ray.tfar = out_->depth[order_[start + k]];
    r.ray.id = k;
    r.hit.geomID = r.hit.primID = r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }
  if (missed == 0) return;
  rtcIntersect1M(scene_->scene(), &context_, again_.data(), missed, sizeof(RTCRayHit));
  stats_.second_rays += missed;
  for (unsigned m = 0; m < missed; ++m) rays_[again_[m].ray.id] = again_[m];
}

void FaceTracer::shade_hits(std::size_t start, unsigned count) {
  if (!colour_ && texturer_.untextured()) {  // only depths and triangles: nothing to prefetch
    for (unsigned k = 0; k < count; ++k)
      if (rays_[k].hit.geomID != RTC_INVALID_GEOMETRY_ID) shade_hit(order_[start + k], rays_[k]);
    return;
  }
  // Hits ahead: their triangles' indices, then (nearer) their corners'
  // attributes, so shading does not wait on each dependent load in turn.
  for (unsigned k = 0; k < count; ++k) {
    if (k + kPrefetchIndicesAhead < count)
      if (const Chunk* c = hit_chunk(*scene_, rays_[k + kPrefetchIndicesAhead]))
        prefetch_triangle_indices(*c, rays_[k + kPrefetchIndicesAhead].hit.primID);
    if (k + kPrefetchAttributesAhead < count)
      if (const Chunk* c = hit_chunk(*scene_, rays_[k + kPrefetchAttributesAhead]))
        prefetch_corner_attributes(*c, rays_[k + kPrefetchAttributesAhead].hit.primID);
    if (rays_[k].hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
    shade_hit(order_[start + k], rays_[k]);
  }
}

void FaceTracer::shade_hit(std::uint32_t p, const RTCRayHit& r) {
  SurfaceHit hit = surface_hit(*scene_, r);
  if (texturer_.untextured()) {
    accept(p, hit, r.ray.tfar, nullptr);
    return;
  }
  const Vec3f dir{r.ray.dir_x, r.ray.dir_y, r.ray.dir_z};
  HitTexel texel = texturer_.texel(hit, dir, r.ray.tfar, step_x_, step_y_);
  float t = r.ray.tfar;
  if (texel.dropped) {
    trace_behind_dropped(r, p, dir, hit, t, texel);
    if (texel.dropped) return;  // nothing opaque behind here
  }
  accept(p, hit, t, texel.textured ? &texel.texel : nullptr);
}

void FaceTracer::trace_behind_dropped(const RTCRayHit& r, std::uint32_t p, const Vec3f& dir, SurfaceHit& hit,
                                      float& t, HitTexel& texel) {
  // Rare: foliage edges.
  const RaySegments seg = ray_segments(Vec3d{dir.x, dir.y, dir.z}, box_, near_plane_);
  const float limit = out_->depth[p];
  RTCIntersectContext single;
  rtcInitIntersectContext(&single);
  // The dropped triangle; Embree may return it again from just past it (an
  // instance's transform rounds the ray's tnear), so each such return moves
  // the start on by a growing relative step.
  unsigned dropped_inst = r.hit.instID[0], dropped_geom = r.hit.geomID, dropped_prim = r.hit.primID;
  float step = 0;
  for (int behind = 0; behind < kMaxAlphaLayers && texel.dropped; ++behind) {
    RTCRayHit next;
    const float from = std::max(std::nextafter(t, std::numeric_limits<float>::infinity()), t + step);
    bool found = false;
    if (from < seg.t1) {
      init_ray(next, scene_->ray_origin(), Vec3d{dir.x, dir.y, dir.z}, std::max(from, seg.t0),
               std::min(seg.t1, limit), p);
      rtcIntersect1(scene_->scene(), &single, &next);
      found = next.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    if (!found && seg.two) {
      init_ray(next, scene_->ray_origin(), Vec3d{dir.x, dir.y, dir.z}, std::max(from, seg.t2), limit, p);
      rtcIntersect1(scene_->scene(), &single, &next);
      found = next.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    ++stats_.alpha_retraces;
    if (!found) break;
    if (next.hit.instID[0] == dropped_inst && next.hit.geomID == dropped_geom && next.hit.primID == dropped_prim) {
      step = step > 0 ? 2 * step : std::max(t, 1.0f) * 1e-6f;
      continue;
    }
    step = 0;
    dropped_inst = next.hit.instID[0], dropped_geom = next.hit.geomID, dropped_prim = next.hit.primID;
    hit = surface_hit(*scene_, next);
    t = next.ray.tfar;
    texel = texturer_.texel(hit, dir, t, step_x_, step_y_);
  }
}

void FaceTracer::accept(std::uint32_t p, const SurfaceHit& hit, float t, const std::array<float, 4>* texel) {
  FaceHits& out = *out_;
  if (!(t < out.depth[p])) return;
  if (colour_) out.color[p] = shader_.shade(hit, texel);
  out.depth[p] = t;
  out.chunk[p] = hit.chunk->id;
  out.triangle[p] = hit.triangle;
  ++stats_.hits;
}

}  // namespace cellbake
