// Ray-cast panoramic samples (issue #12). Embree 3: Wald et al. 2014, "Embree:
// a kernel framework for efficient CPU ray tracing", ACM TOG 33(4); coherent
// streams: Fuetterling et al. 2015, JCGT 4(5); https://www.embree.org/api.html.
#include "stages/raycast/embree_cube_sampler.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "stages/raycast/instance_scene.h"
#include "stages/raycast/ray_segments.h"
#include "stages/far/seen_triangles.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr unsigned kStream = 1024;  // rays per rtcIntersect1M call
// How many hits ahead shading asks for a triangle's indices, and for its
// corners' attributes (prefetch_triangle_indices, prefetch_corner_attributes).
constexpr unsigned kPrefetchIndicesAhead = 32;
constexpr unsigned kPrefetchAttributesAhead = 16;

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

// Alpha-tested layers a ray passes through before it gives up (background).
constexpr int kMaxAlphaLayers = 64;

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

// Per face and pixel, the nearest hit over the batches traced so far: its
// colour, depth (the limit of later batches' rays) and chunk triangle.
struct FaceHits {
  std::vector<Rgba8> color;
  std::vector<float> depth;
  std::vector<std::int64_t> chunk;  // -1: none
  std::vector<std::uint32_t> triangle;
};

// True when no ray of the size x size faces can hit anything inside `box`
// (world) nearer than what it already hit. Per face, in the face's frame
// (right r, up u, forward f; the box's extents there bound it): a ray of the
// face only reaches points with |r| <= f and |u| <= f, so the box's nearest
// reachable depth is f_min = max(f_lo, min |r|, min |u|) (none when above
// f_hi), and its rays are those through the box's projection at depths
// f_min..f_hi (one pixel wider). Hidden when each of those pixels already has
// a depth no greater than f_min (a hit there would not be nearer, and ties
// keep the earlier hit).
bool box_hidden(const Box3d& box, const Vec3d& eye, const std::array<FaceHits, kCubeFaces>& faces, int size) {
  if (box.empty()) return true;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const auto min_abs = [](double lo, double hi) { return lo > 0 ? lo : hi < 0 ? -hi : 0.0; };
  for (int face = 0; face < kCubeFaces; ++face) {
    const FaceBasis b = cube_face_basis(face);
    double r_lo = kInf, r_hi = -kInf, u_lo = kInf, u_hi = -kInf, f_lo = kInf, f_hi = -kInf;
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3d c = Vec3d{corner & 1 ? box.hi.x : box.lo.x, corner & 2 ? box.hi.y : box.lo.y,
                            corner & 4 ? box.hi.z : box.lo.z} - eye;
      const double r = dot(c, b.right), u = dot(c, b.up), f = dot(c, b.forward);
      r_lo = std::min(r_lo, r), r_hi = std::max(r_hi, r);
      u_lo = std::min(u_lo, u), u_hi = std::max(u_hi, u);
      f_lo = std::min(f_lo, f), f_hi = std::max(f_hi, f);
    }
    const double f_min = std::max({f_lo, min_abs(r_lo, r_hi), min_abs(u_lo, u_hi), 1e-9});
    if (f_min > f_hi) continue;  // out of this face's frustum
    // s = r / f and t = u / f over r, u in their ranges and f in [f_min, f_hi].
    const double s_lo = r_lo / (r_lo >= 0 ? f_hi : f_min), s_hi = r_hi / (r_hi >= 0 ? f_min : f_hi);
    const double t_lo = u_lo / (u_lo >= 0 ? f_hi : f_min), t_hi = u_hi / (u_hi >= 0 ? f_min : f_hi);
    // Column of s: (s + 1) / 2 * size - 0.5; row of t: (1 - t) / 2 * size - 0.5.
    const auto index = [size](double v) { return int(std::clamp(v, 0.0, double(size - 1))); };
    const int col0 = index(std::floor((s_lo + 1) / 2 * size - 0.5) - 1), col1 = index(std::ceil((s_hi + 1) / 2 * size - 0.5) + 1);
    const int row0 = index(std::floor((1 - t_hi) / 2 * size - 0.5) - 1), row1 = index(std::ceil((1 - t_lo) / 2 * size - 0.5) + 1);
    const std::vector<float>& depth = faces[std::size_t(face)].depth;
    for (int row = row0; row <= row1; ++row)
      for (int col = col0; col <= col1; ++col)
        if (double(depth[std::size_t(row) * std::size_t(size) + std::size_t(col)]) > f_min) return false;
  }
  return true;
}

}  // namespace

std::vector<std::uint32_t> block_order(int size) {
  std::vector<std::uint32_t> order;
  order.reserve(std::size_t(size) * std::size_t(size));
  for (int band = 0; band < size; band += 4)
    for (int block = 0; block < size; block += 4)
      for (int row = band; row < std::min(size, band + 4); ++row)
        for (int col = block; col < std::min(size, block + 4); ++col)
          order.push_back(std::uint32_t(row) * std::uint32_t(size) + std::uint32_t(col));
  return order;
}

EmbreeCubeSampler::EmbreeCubeSampler(std::shared_ptr<ChunkBvhCache> cache, std::shared_ptr<MipTextureCache> textures)
    : cache_(std::move(cache)),
      textures_(textures ? std::move(textures) : std::make_shared<MipTextureCache>(std::size_t{512} << 20)),
      shader_(shading_lights(ShadingParams{}, Vec3d{0, 0, 1})) {
  if (!cache_) throw std::invalid_argument("embree_cube_sampler: null BVH cache");
}

CubeSample EmbreeCubeSampler::trace_cube(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                                         const ChunkSource& source) {
  validate_sample_inputs(eye, params);
  const HitTexturer texturer(source, *textures_);
  auto t0 = Clock::now();
  // A model that is one group is traced whole: a cube map sees it unless it
  // lies inside the cull box, and the same BVH answers whichever of its
  // chunks the faces see, so the source's chunk query (~5 % of a cube map on
  // the 12.7 M plant) is skipped.
  std::vector<ChunkGroupRefs> groups = cache_->all_groups(source);
  if (groups.size() == 1 && cull_box.strictly_contains(groups.front().bounds)) groups.clear();
  if (groups.size() > 1)
    groups = cache_->groups_of(cube_chunks(eye, cull_box, params.near_plane, source), source);
  std::size_t estimated_bytes = 0;
  for (const ChunkGroupRefs& g : groups) estimated_bytes += g.estimated_bytes;
  const bool one_batch = estimated_bytes <= cache_->one_batch_bytes();
  if (!one_batch) {
    cache_->set_focus(eye);
    // Nearest groups first, so later batches are mostly hidden behind what
    // earlier ones hit and are skipped without being built.
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t i = 0; i < groups.size(); ++i) order.emplace_back(groups[i].bounds.distance_to(eye), i);
    std::sort(order.begin(), order.end());
    std::vector<ChunkGroupRefs> sorted;
    for (const auto& [distance, i] : order) sorted.push_back(std::move(groups[i]));
    groups = std::move(sorted);
  }
  stats_.gather_seconds += seconds_since(t0);

  const int size = params.face_size * params.supersample;
  if (order_size_ != size) {
    order_ = block_order(size);
    coordinate_.resize(std::size_t(size));
    inverse_coordinate_.resize(std::size_t(size));
    for (int i = 0; i < size; ++i) {
      coordinate_[std::size_t(i)] = 2.0 * (i + 0.5) / size - 1.0;  // 0 (odd sizes): slab_interval handles it
      inverse_coordinate_[std::size_t(i)] = 1.0 / coordinate_[std::size_t(i)];
    }
    tile_of_ = pixel_tiles(size);
    order_size_ = size;
  }
  const EyeBox box = eye_relative_box(cull_box, eye);
  const std::size_t pixels = std::size_t(size) * std::size_t(size);
  std::array<FaceHits, kCubeFaces> faces;
  for (FaceHits& f : faces) {
    f.color.assign(pixels, Rgba8{0, 0, 0, 0});
    f.depth.assign(pixels, kBackgroundDepth);
    f.chunk.assign(pixels, -1);
    f.triangle.assign(pixels, 0);
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  std::vector<RTCRayHit> rays(kStream), again(kStream);
  std::vector<float> second(kStream);  // where each ray's second segment starts (inf: none)
  for (std::size_t next = 0; next < groups.size();) {
    // The next batch: every group when all fit (as one scene); else groups in
    // order up to the batch bytes, skipping those hidden behind earlier hits.
    t0 = Clock::now();
    std::vector<std::size_t> batch;  // groups
    std::size_t bytes = 0;
    for (; next < groups.size(); ++next) {
      const ChunkGroupRefs& g = groups[next];
      if (!one_batch && box_hidden(g.bounds, eye, faces, size)) {
        ++stats_.groups_hidden;
        continue;
      }
      if (!one_batch && !batch.empty() && bytes + g.estimated_batch_bytes > cache_->batch_bytes()) break;
      batch.push_back(g.group);
      bytes += g.estimated_batch_bytes;
    }
    if (batch.empty()) break;
    std::vector<std::shared_ptr<const ChunkGroupBvh>> bvhs =
        cache_->acquire_groups(std::move(batch), source, !one_batch);
    stats_.gather_seconds += seconds_since(t0);
    t0 = Clock::now();
    const InstanceScene scene(*cache_, std::move(bvhs), eye);
    stats_.scene_seconds += seconds_since(t0);
    stats_.instances += scene.size();
    ++stats_.batches;
    t0 = Clock::now();
    for (int face = 0; face < kCubeFaces; ++face) {
      FaceHits& out = faces[std::size_t(face)];
      const FaceBasis b = cube_face_basis(face);
      const auto to_float = [](const Vec3d& v) { return Vec3f{float(v.x), float(v.y), float(v.z)}; };
      const Vec3f step_x = to_float(b.right * (2.0 / size)), step_y = to_float(b.up * (2.0 / size));
      // A hit counts only when strictly nearer than an earlier batch's: ties
      // keep the earlier one (with one batch, the limit is +inf throughout).
      const auto accept = [&](std::uint32_t p, const SurfaceHit& hit, float t, const std::array<float, 4>* texel) {
        if (!(t < out.depth[p])) return;
        out.color[p] = shader_.shade(hit, texel);
        out.depth[p] = t;
        out.chunk[p] = hit.chunk->id;
        out.triangle[p] = hit.triangle;
        ++stats_.hits;
      };
      face_slabs_.set(b, box, coordinate_, inverse_coordinate_);
      for (std::size_t start = 0; start < pixels; start += kStream) {
        const unsigned count = unsigned(std::min<std::size_t>(kStream, pixels - start));
        for (unsigned k = 0; k < count; ++k) {
          const std::uint32_t p = order_[start + k];
          const std::uint32_t row = p / std::uint32_t(size), col = p - row * std::uint32_t(size);
          const Vec3d dir = cube_face_direction(b, coordinate_[col], -coordinate_[row]);
          const RaySegments seg = face_slabs_.segments(col, row, params.near_plane);
          init_ray(rays[k], scene.ray_origin(), dir, seg.t0, std::min(seg.t1, out.depth[p]), p);
          second[k] = seg.two && seg.t2 < out.depth[p] ? seg.t2 : std::numeric_limits<float>::infinity();
        }
        rtcIntersect1M(scene.scene(), &context, rays.data(), count, sizeof(RTCRayHit));
        stats_.rays += count;
        // Rays that missed their first segment and have a second one: trace that.
        unsigned missed = 0;
        for (unsigned k = 0; k < count; ++k) {
          if (rays[k].hit.geomID != RTC_INVALID_GEOMETRY_ID || std::isinf(second[k])) continue;
          RTCRayHit& r = again[missed++];
          r = rays[k];
          r.ray.tnear = second[k];
          r.ray.tfar = out.depth[order_[start + k]];
          r.ray.id = k;
          r.hit.geomID = r.hit.primID = r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        }
        if (missed > 0) {
          rtcIntersect1M(scene.scene(), &context, again.data(), missed, sizeof(RTCRayHit));
          stats_.second_rays += missed;
          for (unsigned m = 0; m < missed; ++m) rays[again[m].ray.id] = again[m];
        }
        // Hits ahead: their triangles' indices, then (nearer) their corners'
        // attributes, so shading does not wait on each dependent load in turn.
        for (unsigned k = 0; k < count; ++k) {
          if (k + kPrefetchIndicesAhead < count)
            if (const Chunk* c = hit_chunk(scene, rays[k + kPrefetchIndicesAhead]))
              prefetch_triangle_indices(*c, rays[k + kPrefetchIndicesAhead].hit.primID);
          if (k + kPrefetchAttributesAhead < count)
            if (const Chunk* c = hit_chunk(scene, rays[k + kPrefetchAttributesAhead]))
              prefetch_corner_attributes(*c, rays[k + kPrefetchAttributesAhead].hit.primID);
          const RTCRayHit& r = rays[k];
          if (r.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
          const std::uint32_t p = order_[start + k];
          SurfaceHit hit = surface_hit(scene, r);
          if (texturer.untextured()) {
            accept(p, hit, r.ray.tfar, nullptr);
            continue;
          }
          const Vec3f dir{r.ray.dir_x, r.ray.dir_y, r.ray.dir_z};
          HitTexel texel = texturer.texel(hit, dir, r.ray.tfar, step_x, step_y);
          float t = r.ray.tfar;
          if (texel.dropped) {
            // Alpha-tested away: go on behind it, one hit at a time, within the
            // ray's segments up to the nearest earlier hit (rare: foliage edges).
            const RaySegments seg = ray_segments(Vec3d{dir.x, dir.y, dir.z}, box, params.near_plane);
            const float limit = out.depth[p];
            RTCIntersectContext single;
            rtcInitIntersectContext(&single);
            // The dropped triangle; Embree may return it again from just past
            // it (an instance's transform rounds the ray's tnear), so each
            // such return moves the start on by a growing relative step.
            unsigned dropped_inst = r.hit.instID[0], dropped_geom = r.hit.geomID, dropped_prim = r.hit.primID;
            float step = 0;
            for (int behind = 0; behind < kMaxAlphaLayers && texel.dropped; ++behind) {
              RTCRayHit next;
              const float from = std::max(std::nextafter(t, std::numeric_limits<float>::infinity()), t + step);
              bool found = false;
              if (from < seg.t1) {
                init_ray(next, scene.ray_origin(), Vec3d{dir.x, dir.y, dir.z}, std::max(from, seg.t0),
                         std::min(seg.t1, limit), p);
                rtcIntersect1(scene.scene(), &single, &next);
                found = next.hit.geomID != RTC_INVALID_GEOMETRY_ID;
              }
              if (!found && seg.two) {
                init_ray(next, scene.ray_origin(), Vec3d{dir.x, dir.y, dir.z}, std::max(from, seg.t2), limit,
                         p);
                rtcIntersect1(scene.scene(), &single, &next);
                found = next.hit.geomID != RTC_INVALID_GEOMETRY_ID;
              }
              ++stats_.alpha_retraces;
              if (!found) break;
              if (next.hit.instID[0] == dropped_inst && next.hit.geomID == dropped_geom &&
                  next.hit.primID == dropped_prim) {
                step = step > 0 ? 2 * step : std::max(t, 1.0f) * 1e-6f;
                continue;
              }
              step = 0;
              dropped_inst = next.hit.instID[0], dropped_geom = next.hit.geomID, dropped_prim = next.hit.primID;
              hit = surface_hit(scene, next);
              t = next.ray.tfar;
              texel = texturer.texel(hit, dir, t, step_x, step_y);
            }
            if (texel.dropped) continue;  // nothing opaque behind here
          }
          accept(p, hit, t, texel.textured ? &texel.texel : nullptr);
        }
      }
    }
    cache_->check_device("tracing a cube map");
    stats_.trace_seconds += seconds_since(t0);
    // This batch's scene is gone: its BVHs may make room for the next batch.
    if (!one_batch) cache_->trim();
  }

  t0 = Clock::now();
  CubeSample sample;
  sample.eye = eye;
  SeenScratch scratch;
  for (int face = 0; face < kCubeFaces; ++face) {
    FaceHits& hits = faces[std::size_t(face)];
    CubeFace& out = sample.faces[std::size_t(face)];
    out = finish_face(hits.color, hits.depth, params);
    out.seen = seen_triangles(hits.chunk, hits.triangle, tile_of_, scratch);
  }
  stats_.trace_seconds += seconds_since(t0);
  ++stats_.cube_maps;
  return sample;
}

CubeSample EmbreeCubeSampler::sample(const Vec3d& eye, const Box3d& cull_box, const SampleParams& params,
                                     const ChunkSource& source) {
  CubeSample result = trace_cube(eye, cull_box, params, source);
  cache_->trim();  // the cube map's scene is gone: its BVHs may be evicted now
  return result;
}

}  // namespace cellbake
