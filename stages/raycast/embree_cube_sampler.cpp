// Ray-cast panoramic samples (issue #12). Embree 3: Wald et al. 2014, "Embree:
// a kernel framework for efficient CPU ray tracing", ACM TOG 33(4); coherent
// streams: Fuetterling et al. 2015, JCGT 4(5); https://www.embree.org/api.html.
#include "stages/raycast/embree_cube_sampler.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "stages/raycast/instance_scene.h"
#include "stages/raycast/ray_segments.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr unsigned kStream = 1024;  // rays per rtcIntersect1M call

void init_ray(RTCRayHit& r, const Vec3d& dir, float tnear, float tfar, unsigned id) {
  r.ray.org_x = r.ray.org_y = r.ray.org_z = 0;
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

// The chunk triangle and barycentrics of a ray's hit in `scene`.
SurfaceHit surface_hit(const InstanceScene& scene, const RTCRayHit& r) {
  const ChunkGroupBvh& group = scene.instance(r.hit.instID[0]);
  SurfaceHit hit;
  hit.chunk = group.chunks[r.hit.geomID].get();
  hit.triangle = r.hit.primID;
  hit.u = r.hit.u;
  hit.v = r.hit.v;
  hit.geometric_normal = {r.hit.Ng_x, r.hit.Ng_y, r.hit.Ng_z};  // instances only translate
  return hit;
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
  const std::vector<ChunkRef> refs = cube_chunks(eye, cull_box, params.near_plane, source);
  std::vector<std::shared_ptr<const ChunkGroupBvh>> bvhs = cache_->acquire(refs, source);
  stats_.gather_seconds += seconds_since(t0);
  t0 = Clock::now();
  const InstanceScene scene(*cache_, std::move(bvhs), eye);
  stats_.scene_seconds += seconds_since(t0);
  stats_.instances += scene.size();
  t0 = Clock::now();

  const int size = params.face_size * params.supersample;
  if (order_size_ != size) {
    order_ = block_order(size);
    coordinate_.resize(std::size_t(size));
    for (int i = 0; i < size; ++i) coordinate_[std::size_t(i)] = 2.0 * (i + 0.5) / size - 1.0;
    order_size_ = size;
  }
  const EyeBox box = eye_relative_box(cull_box, eye);
  const std::size_t pixels = std::size_t(size) * std::size_t(size);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  std::vector<RTCRayHit> rays(kStream), again(kStream);
  std::vector<float> second(kStream);  // where each ray's second segment starts (inf: none)
  std::vector<Rgba8> color;
  std::vector<float> depth;
  CubeSample sample;
  sample.eye = eye;
  std::vector<std::uint32_t> tile_of(pixels);
  for (std::size_t p = 0; p < pixels; ++p) tile_of[p] = std::uint32_t(pixel_tile(int(p % std::size_t(size)), int(p / std::size_t(size)), size));
  // What each face saw: chunk -> per-triangle tile masks (dense while tracing,
  // compacted when the face is done); runs of one chunk and tile are common.
  std::unordered_map<const Chunk*, std::size_t> slot_of;
  std::vector<std::pair<const Chunk*, std::vector<std::uint16_t>>> slots;
  for (int face = 0; face < kCubeFaces; ++face) {
    const FaceBasis b = cube_face_basis(face);
    slot_of.clear();
    slots.clear();
    const Chunk* last_chunk = nullptr;
    std::vector<std::uint16_t>* last_tiles = nullptr;
    const auto saw = [&](const SurfaceHit& hit, std::uint32_t p) {
      if (hit.chunk != last_chunk) {
        auto [it, added] = slot_of.try_emplace(hit.chunk, slots.size());
        if (added) slots.emplace_back(hit.chunk, std::vector<std::uint16_t>(hit.chunk->triangle_count(), 0));
        last_chunk = hit.chunk;
        last_tiles = &slots[it->second].second;
      }
      (*last_tiles)[hit.triangle] |= std::uint16_t(1u << tile_of[p]);
    };
    const auto to_float = [](const Vec3d& v) { return Vec3f{float(v.x), float(v.y), float(v.z)}; };
    const Vec3f step_x = to_float(b.right * (2.0 / size)), step_y = to_float(b.up * (2.0 / size));
    color.assign(pixels, Rgba8{0, 0, 0, 0});
    depth.assign(pixels, kBackgroundDepth);
    for (std::size_t start = 0; start < pixels; start += kStream) {
      const unsigned count = unsigned(std::min<std::size_t>(kStream, pixels - start));
      for (unsigned k = 0; k < count; ++k) {
        const std::uint32_t p = order_[start + k];
        const std::uint32_t row = p / std::uint32_t(size), col = p - row * std::uint32_t(size);
        const Vec3d dir = cube_face_direction(b, coordinate_[col], -coordinate_[row]);
        const RaySegments seg = ray_segments(dir, box, params.near_plane);
        init_ray(rays[k], dir, seg.t0, seg.t1, p);
        second[k] = seg.two ? seg.t2 : std::numeric_limits<float>::infinity();
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
        r.ray.tfar = std::numeric_limits<float>::infinity();
        r.ray.id = k;
        r.hit.geomID = r.hit.primID = r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      if (missed > 0) {
        rtcIntersect1M(scene.scene(), &context, again.data(), missed, sizeof(RTCRayHit));
        stats_.second_rays += missed;
        for (unsigned m = 0; m < missed; ++m) rays[again[m].ray.id] = again[m];
      }
      for (unsigned k = 0; k < count; ++k) {
        const RTCRayHit& r = rays[k];
        if (r.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        const std::uint32_t p = order_[start + k];
        SurfaceHit hit = surface_hit(scene, r);
        if (texturer.untextured()) {
          color[p] = shader_.shade(hit);
          depth[p] = r.ray.tfar;
          saw(hit, p);
          ++stats_.hits;
          continue;
        }
        const Vec3f dir{r.ray.dir_x, r.ray.dir_y, r.ray.dir_z};
        HitTexel texel = texturer.texel(hit, dir, r.ray.tfar, step_x, step_y);
        float t = r.ray.tfar;
        if (texel.dropped) {
          // Alpha-tested away: go on behind it, one hit at a time, within the
          // ray's segments (rare: foliage edges).
          const RaySegments seg = ray_segments(Vec3d{dir.x, dir.y, dir.z}, box, params.near_plane);
          RTCIntersectContext single;
          rtcInitIntersectContext(&single);
          for (int behind = 0; behind < kMaxAlphaLayers && texel.dropped; ++behind) {
            RTCRayHit next;
            const float from = std::nextafter(t, std::numeric_limits<float>::infinity());
            bool found = false;
            if (from < seg.t1) {
              init_ray(next, Vec3d{dir.x, dir.y, dir.z}, std::max(from, seg.t0), seg.t1, p);
              rtcIntersect1(scene.scene(), &single, &next);
              found = next.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
            if (!found && seg.two) {
              init_ray(next, Vec3d{dir.x, dir.y, dir.z}, std::max(from, seg.t2),
                       std::numeric_limits<float>::infinity(), p);
              rtcIntersect1(scene.scene(), &single, &next);
              found = next.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
            ++stats_.alpha_retraces;
            if (!found) break;
            hit = surface_hit(scene, next);
            t = next.ray.tfar;
            texel = texturer.texel(hit, dir, t, step_x, step_y);
          }
          if (texel.dropped) continue;  // nothing opaque behind: background
        }
        color[p] = shader_.shade(hit, texel.textured ? &texel.texel : nullptr);
        depth[p] = t;
        saw(hit, p);
        ++stats_.hits;
      }
    }
    CubeFace& out = sample.faces[std::size_t(face)];
    out = finish_face(color, depth, params);
    out.seen.reserve(slots.size());
    for (const auto& [chunk, tiles] : slots) {
      SeenChunk seen;
      seen.id = chunk->id;
      for (std::size_t t = 0; t < tiles.size(); ++t)
        if (tiles[t]) {
          seen.triangles.push_back(std::uint32_t(t));
          seen.triangle_tiles.push_back(tiles[t]);
          seen.tiles |= tiles[t];
        }
      out.seen.push_back(std::move(seen));
    }
    std::sort(out.seen.begin(), out.seen.end(), [](const SeenChunk& a, const SeenChunk& b) { return a.id < b.id; });
  }
  cache_->check_device("tracing a cube map");
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
