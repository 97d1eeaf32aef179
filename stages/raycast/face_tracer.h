// The hot loop of the Embree sampling backend (embree_cube_sampler.h): one
// cube face's rays traced against one batch's instance scene. Pixels go in
// 4 x 4 block order (block_order) in coherent streams of 1024 rays
// (rtcIntersect1M with RTC_INTERSECT_CONTEXT_FLAG_COHERENT); each ray covers
// its first segment outside the cull box (ray_segments.h), and a ray that
// missed it and has a second segment is traced again over that one. Hits are
// shaded (hit_shading.h) and textured (hit_texturing.h); a hit an alpha test
// drops is traced again from just behind it. Per pixel the nearest hit is
// kept, a later batch's only when strictly nearer (ties keep the earlier).
//
// Embree 3: Wald et al. 2014, "Embree: a kernel framework for efficient CPU
// ray tracing", ACM TOG 33(4); coherent streams: Fuetterling et al. 2015,
// JCGT 4(5); https://www.embree.org/api.html.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <span>
#include <vector>

#include "stages/cube_map.h"
#include "stages/raycast/hit_shading.h"
#include "stages/raycast/hit_texturing.h"
#include "stages/raycast/instance_scene.h"
#include "stages/raycast/ray_segments.h"

namespace cellbake {

struct EmbreeSamplerStats;  // embree_cube_sampler.h

// Per face and pixel, the nearest hit over the batches traced so far: its
// colour, depth (the limit of later batches' rays) and chunk triangle.
struct FaceHits {
  std::vector<Rgba8> color;
  std::vector<float> depth;
  std::vector<std::int64_t> chunk;  // -1: none
  std::vector<std::uint32_t> triangle;

  // `pixels` pixels with no hit yet: transparent black at kBackgroundDepth.
  void clear(std::size_t pixels);
};

// Traces the faces of one cube map, batch by batch. Not thread-safe; one per
// cube map. Everything the constructor is given must outlive the tracer.
class FaceTracer {
 public:
  // For size x size faces whose pixels go in `order` (block_order(size)),
  // column i and row i at s = coordinate[i] and t = -coordinate[i]
  // (inverse_coordinate[i] = 1.0 / coordinate[i]), rays limited to their
  // segments beyond `near_plane` outside `box` (the cull box relative to the
  // eye); `slabs` is scratch for the face being traced. Hits are shaded by
  // `shader` (unless not `colour`: colours stay transparent black) and
  // textured by `texturer` (alpha tests apply either way); rays, second
  // rays, hits and alpha retraces are counted in `stats`.
  FaceTracer(const HitShader& shader, const HitTexturer& texturer, const EyeBox& box, double near_plane, int size,
             std::span<const std::uint32_t> order, std::span<const double> coordinate,
             std::span<const double> inverse_coordinate, FaceSlabs& slabs, EmbreeSamplerStats& stats,
             bool colour = true);

  // Traces face `face`'s rays against `scene`, each limited to the depth in
  // `out` at its pixel, and keeps there every hit strictly nearer.
  void trace(const InstanceScene& scene, int face, FaceHits& out);

 private:
  // Steps of trace(), for the rays of order[start, start + count).
  // Primary rays (first segments, up to the pixel's depth) and where each
  // ray's second segment starts (inf: none).
  void set_up_rays(std::size_t start, unsigned count);
  // Traces the second segment of each ray that missed its first one, in
  // place of that ray's result.
  void trace_second_segments(std::size_t start, unsigned count);
  // Shades the stream's hits in order, prefetching the data of hits ahead.
  void shade_hits(std::size_t start, unsigned count);
  // Shades and textures the hit `r` of pixel `p`, going on behind it when an
  // alpha test drops it, and keeps the result when it is nearer.
  void shade_hit(std::uint32_t p, const RTCRayHit& r);
  // After `hit` at `t` was alpha-tested away (texel.dropped), traces the ray
  // (direction `dir`, pixel `p`) on behind it, one hit at a time within its
  // segments up to the pixel's depth, until a hit is kept by its texel
  // (texel.dropped false) or none is left (texel.dropped stays true);
  // `hit`, `t` and `texel` end as the last hit's.
  void trace_behind_dropped(const RTCRayHit& r, std::uint32_t p, const Vec3f& dir, SurfaceHit& hit, float& t,
                            HitTexel& texel);
  // Keeps `hit` at depth t for pixel p when strictly nearer than its depth.
  void accept(std::uint32_t p, const SurfaceHit& hit, float t, const std::array<float, 4>* texel);

  // Per cube map.
  const HitShader& shader_;
  const HitTexturer& texturer_;
  EyeBox box_;
  double near_plane_;
  bool colour_;
  int size_;
  std::size_t pixels_;
  std::span<const std::uint32_t> order_;
  std::span<const double> coordinate_, inverse_coordinate_;
  FaceSlabs& slabs_;
  EmbreeSamplerStats& stats_;
  RTCIntersectContext context_;
  std::vector<RTCRayHit> rays_, again_;
  std::vector<float> second_;  // where each ray's second segment starts (inf: none)
  // Per face (set by trace()).
  const InstanceScene* scene_ = nullptr;
  FaceHits* out_ = nullptr;
  FaceBasis basis_;
  Vec3f step_x_, step_y_;  // one pixel along the face's right and up axes at unit depth
};

}  // namespace cellbake
