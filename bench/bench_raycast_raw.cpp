// Raw Embree on the rays of the Embree sampler (issue #12): the same cells,
// eyes, cull boxes, BVH cache and top-level scenes as bench_sample's
// BM_SampleStoreEmbree, and the same rays (one per pixel centre of six 512^2
// faces, [near, inf) cut where they run inside the cull box), traced without
// shading, second segments, downsampling or any other bookkeeping, in four
// ways: coherent streams of 1024 rays (rtcIntersect1M, what the sampler uses),
// the same streams flagged incoherent, 16-wide packets over 4 x 4 pixel blocks
// (rtcIntersect16) and single rays (rtcIntersect1). Also reports the BVH build
// (triangles per thread-second, loading from the store excluded and
// included), the process's peak RSS, and the sampler itself (EmbreeCubeSampler,
// the same cells and cache) alternating rep by rep with raw coherent streams:
// sampler / raw measured side by side.
//
//   CELLBAKE_BENCH_STORE=/tmp/h1/plant.store.db build/bench/bench_raycast_raw [face_size=512] [repetitions=5]
//     [robust|fast|compact] [low|medium|high] [group_triangles] [flat]
// (CELLBAKE_BENCH_EYES="x,y,z;..." picks the eyes, as for bench_sample). The
// third and fourth arguments pick the chunk scenes' flags and build quality
// (default: fast = not robust, medium, as the sampler), the fifth the triangles per chunk
// group (default 0, as the sampler: one group when the model fits one batch of the cache, else
// 1 M; 1: one instance per chunk; 1048576 was the sampler's default before 2026-12-03); `flat` also traces a
// one-level scene per cell holding every needed chunk's triangles directly (the cost of instancing).
//
// Single-threaded tracing; times are per cube map, medians over repetitions.
#include <embree3/rtcore.h>
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_store_eyes.h"
#include "runner/heap_tuning.h"
#include "stages/cube_map.h"
#include "stages/cull_box.h"
#include "stages/raycast/chunk_bvh_cache.h"
#include "stages/raycast/embree_cube_sampler.h"
#include "stages/raycast/instance_scene.h"
#include "stages/raycast/ray_segments.h"
#include "stages/sample/sample.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

struct Cell {
  Vec3d eye;
  Box3d cull;
};

// One cube map's rays: direction and first segment per pixel, in block order.
struct Rays {
  float origin[3] = {0, 0, 0};  // InstanceScene::ray_origin()
  std::vector<float> dir;       // 3 per ray
  std::vector<float> tnear, tfar;
};

Rays make_rays(const Cell& cell, int size, double near, const std::vector<std::uint32_t>& order) {
  Rays r;
  const EyeBox box = eye_relative_box(cell.cull, cell.eye);
  for (int face = 0; face < kCubeFaces; ++face) {
    const FaceBasis b = cube_face_basis(face);
    for (std::uint32_t p : order) {
      const int row = int(p / std::uint32_t(size)), col = int(p % std::uint32_t(size));
      const Vec3d dir = cube_face_direction(b, 2.0 * (col + 0.5) / size - 1.0, 1.0 - 2.0 * (row + 0.5) / size);
      const RaySegments s = ray_segments(dir, box, near);
      r.dir.insert(r.dir.end(), {float(dir.x), float(dir.y), float(dir.z)});
      r.tnear.push_back(s.t0);
      r.tfar.push_back(s.t1);
    }
  }
  return r;
}

void set_ray(RTCRayHit& h, const Rays& r, std::size_t i) {
  h.ray.org_x = r.origin[0];
  h.ray.org_y = r.origin[1];
  h.ray.org_z = r.origin[2];
  h.ray.dir_x = r.dir[3 * i];
  h.ray.dir_y = r.dir[3 * i + 1];
  h.ray.dir_z = r.dir[3 * i + 2];
  h.ray.tnear = r.tnear[i];
  h.ray.tfar = r.tfar[i];
  h.ray.time = 0;
  h.ray.mask = 0xFFFFFFFFu;
  h.ray.id = unsigned(i);
  h.ray.flags = 0;
  h.hit.geomID = h.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

std::size_t trace_stream(RTCScene scene, const Rays& r, bool coherent) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  constexpr std::size_t kStream = 1024;
  std::vector<RTCRayHit> rays(kStream);
  std::size_t hits = 0;
  const std::size_t n = r.tnear.size();
  for (std::size_t start = 0; start < n; start += kStream) {
    const std::size_t count = std::min(kStream, n - start);
    for (std::size_t k = 0; k < count; ++k) set_ray(rays[k], r, start + k);
    rtcIntersect1M(scene, &context, rays.data(), unsigned(count), sizeof(RTCRayHit));
    for (std::size_t k = 0; k < count; ++k) hits += rays[k].hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

std::size_t trace_single(RTCScene scene, const Rays& r) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  std::size_t hits = 0;
  RTCRayHit h;
  for (std::size_t i = 0; i < r.tnear.size(); ++i) {
    set_ray(h, r, i);
    rtcIntersect1(scene, &context, &h);
    hits += h.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

// Block order puts each 4 x 4 block in 16 consecutive rays (size a multiple of 4).
std::size_t trace_packets16(RTCScene scene, const Rays& r) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  std::size_t hits = 0;
  alignas(64) RTCRayHit16 p;
  alignas(64) int valid[16];
  const std::size_t n = r.tnear.size();
  for (std::size_t start = 0; start < n; start += 16) {
    for (int k = 0; k < 16; ++k) {
      const std::size_t i = start + std::size_t(k);
      valid[k] = i < n ? -1 : 0;
      const std::size_t j = std::min(i, n - 1);
      p.ray.org_x[k] = r.origin[0];
      p.ray.org_y[k] = r.origin[1];
      p.ray.org_z[k] = r.origin[2];
      p.ray.dir_x[k] = r.dir[3 * j];
      p.ray.dir_y[k] = r.dir[3 * j + 1];
      p.ray.dir_z[k] = r.dir[3 * j + 2];
      p.ray.tnear[k] = r.tnear[j];
      p.ray.tfar[k] = r.tfar[j];
      p.ray.time[k] = 0;
      p.ray.mask[k] = 0xFFFFFFFFu;
      p.ray.id[k] = unsigned(j);
      p.ray.flags[k] = 0;
      p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      p.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, scene, &context, &p);
    for (int k = 0; k < 16; ++k) hits += valid[k] && p.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
  }
  return hits;
}

int run(int argc, char** argv) {
  const char* path = std::getenv("CELLBAKE_BENCH_STORE");
  if (!path) {
    std::fprintf(stderr, "set CELLBAKE_BENCH_STORE to a geometry store\n");
    return 2;
  }
  const int size = argc > 1 ? std::atoi(argv[1]) : 512;
  const int repetitions = std::max(5, argc > 2 ? std::atoi(argv[2]) : 5);
  const double near = 0.01;
  const GeometryStore store(path);
  std::vector<Cell> cells;
  for (const Vec3d& eye : bench_eyes(store.model_bounds())) {
    CullBoxParams cull;
    cull.min_half_size = 2.0;  // as bench_sample: 4 m cells
    cells.push_back({eye, Box3d::cube(eye, find_cull_box(eye, cull, store).half_size)});
  }
  std::printf("store %s, %zu cells, %d^2 x 6 rays per cube map, rss after cull boxes %.0f MiB\n", path, cells.size(),
              size, peak_rss_mib());

  // BVH builds: every chunk the cells need, once (cold cache).
  ChunkBvhCacheParams cache_params;
  const std::string flags = argc > 3 ? argv[3] : "fast", quality = argc > 4 ? argv[4] : "medium";
  const bool flat = argc > 6 && std::string(argv[6]) == "flat";
  if (argc > 5) cache_params.group_triangles = std::size_t(std::atoll(argv[5]));
  cache_params.scene_flags = flags == "robust"    ? RTC_SCENE_FLAG_ROBUST
                            : flags == "compact" ? RTC_SCENE_FLAG_COMPACT
                                                 : RTC_SCENE_FLAG_NONE;
  cache_params.build_quality = quality == "high"  ? RTC_BUILD_QUALITY_HIGH
                               : quality == "low" ? RTC_BUILD_QUALITY_LOW
                                                  : RTC_BUILD_QUALITY_MEDIUM;
  std::printf("chunk scenes: %s, %s build quality, groups of <= %zu triangles\n", flags.c_str(), quality.c_str(),
              cache_params.group_triangles);
  auto cache = std::make_shared<ChunkBvhCache>(cache_params);
  std::vector<std::unique_ptr<InstanceScene>> scenes;
  const auto t_build = Clock::now();
  const double cpu_build = process_cpu_seconds();
  double top_seconds = 0;
  std::size_t instances = 0;
  for (const Cell& c : cells) {
    auto bvhs = cache->acquire(cube_chunks(c.eye, c.cull, near, store), store);
    const auto t_top = Clock::now();
    scenes.push_back(std::make_unique<InstanceScene>(*cache, std::move(bvhs), c.eye));
    top_seconds += seconds_since(t_top);
    instances += scenes.back()->size();
  }
  const double build_wall = seconds_since(t_build), build_cpu = process_cpu_seconds() - cpu_build;
  const ChunkBvhCacheStats s = cache->stats();
  std::printf("BVH: %llu chunks, %.2f M triangles; %.2f s in load+build (%.2f s loading) => %.2f M tri/s built "
              "(load excluded), %.2f M tri/s with loading; wall %.2f s, process CPU %.2f s => %.2f M tri per CPU-s "
              "(everything: cube_chunks, loads, builds, top-level scenes); device memory %.0f MiB (peak %.0f), "
              "chunk arrays %.0f MiB\n",
              (unsigned long long)s.builds, s.triangles_built / 1e6, s.build_seconds, s.load_seconds,
              s.triangles_built / 1e6 / std::max(1e-9, s.build_seconds - s.load_seconds),
              s.triangles_built / 1e6 / std::max(1e-9, s.build_seconds), build_wall, build_cpu,
              s.triangles_built / 1e6 / std::max(1e-9, build_cpu), s.device_bytes / 1048576.0,
              s.peak_device_bytes / 1048576.0, s.chunk_bytes / 1048576.0);
  std::printf("%zu groups; top-level scenes: %.2f ms per cube map, %.0f instances per cube map\n", s.groups,
              1e3 * top_seconds / double(cells.size()), double(instances) / double(cells.size()));

  const std::vector<std::uint32_t> order = block_order(size);
  std::vector<Rays> rays;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    rays.push_back(make_rays(cells[i], size, near, order));
    const Vec3f& o = scenes[i]->ray_origin();
    rays.back().origin[0] = o.x, rays.back().origin[1] = o.y, rays.back().origin[2] = o.z;
  }
  const std::size_t rays_per_cube = std::size_t(6) * std::size_t(size) * std::size_t(size);

  struct Mode {
    const char* name;
    std::function<std::size_t(RTCScene, const Rays&)> trace;
  };
  const std::vector<Mode> modes = {
      {"rtcIntersect1M coherent", [](RTCScene sc, const Rays& r) { return trace_stream(sc, r, true); }},
      {"rtcIntersect1M incoherent", [](RTCScene sc, const Rays& r) { return trace_stream(sc, r, false); }},
      {"rtcIntersect16 4x4 blocks", [](RTCScene sc, const Rays& r) { return trace_packets16(sc, r); }},
      {"rtcIntersect1", [](RTCScene sc, const Rays& r) { return trace_single(sc, r); }},
  };
  if (flat) {
    // One-level scenes: every needed chunk's triangles, translated into the eye frame, in one BVH per cell.
    std::vector<RTCScene> flat_scenes;
    double flat_build = 0;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const auto t0 = Clock::now();
      RTCScene sc = rtcNewScene(cache->device());
      rtcSetSceneFlags(sc, static_cast<RTCSceneFlags>(cache_params.scene_flags));
      rtcSetSceneBuildQuality(sc, cache_params.build_quality);
      for (std::size_t k = 0; k < scenes[i]->size(); ++k)
        for (const auto& chunk : scenes[i]->instance(unsigned(k)).chunks) {
        const Chunk& c = *chunk;
        if (c.triangle_count() == 0) continue;
        const Vec3d o = c.origin - cells[i].eye;
        RTCGeometry g = rtcNewGeometry(cache->device(), RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), c.positions.size()));
        for (std::size_t j = 0; j < c.positions.size(); ++j) {
          v[3 * j] = c.positions[j].x + float(o.x);
          v[3 * j + 1] = c.positions[j].y + float(o.y);
          v[3 * j + 2] = c.positions[j].z + float(o.z);
        }
        auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(unsigned), c.triangle_count()));
        std::copy(c.indices.begin(), c.indices.end(), idx);
        rtcCommitGeometry(g);
        rtcAttachGeometry(sc, g);
        rtcReleaseGeometry(g);
      }
      rtcCommitScene(sc);
      flat_build += seconds_since(t0);
      flat_scenes.push_back(sc);
    }
    std::vector<Rays> eye_rays = rays;  // the flat scenes are in the eye's frame
    for (Rays& r : eye_rays) r.origin[0] = r.origin[1] = r.origin[2] = 0;
    std::vector<double> per_cube;
    for (int rep = 0; rep < repetitions; ++rep) {
      const auto t0 = Clock::now();
      for (std::size_t i = 0; i < cells.size(); ++i) trace_stream(flat_scenes[i], eye_rays[i], true);
      per_cube.push_back(seconds_since(t0) / double(cells.size()));
    }
    std::printf("%-28s %8.2f ms per cube map (median of %d); one-level build %.0f ms per cell\n",
                "flat 1M coherent", 1e3 * median(per_cube), repetitions, 1e3 * flat_build / double(cells.size()));
    for (RTCScene sc : flat_scenes) rtcReleaseScene(sc);
  }
  for (const Mode& m : modes) {
    std::vector<double> per_cube;
    std::size_t hits = 0;
    for (int rep = 0; rep < repetitions; ++rep) {
      const auto t0 = Clock::now();
      hits = 0;
      for (std::size_t i = 0; i < cells.size(); ++i) hits += m.trace(scenes[i]->scene(), rays[i]);
      per_cube.push_back(seconds_since(t0) / double(cells.size()));
    }
    const double t = median(per_cube);
    std::printf("%-28s %8.2f ms per cube map (median of %d), %6.1f Mrays/s, %.3f hit fraction\n", m.name, 1e3 * t,
                repetitions, double(rays_per_cube) / t / 1e6, double(hits) / double(rays_per_cube * cells.size()));
  }
  // The sampler on the same cells, BVH cache and rays, alternating with raw
  // coherent streams rep by rep, so that both see the machine at the same
  // speed (shared machines drift by tens of percent within minutes): the
  // sampler's overhead as a ratio measured side by side.
  EmbreeCubeSampler sampler(cache);
  SampleParams params;
  params.face_size = size;
  params.near_plane = near;
  std::vector<double> sampler_per_cube, raw_per_cube, ratios;
  for (int rep = 0; rep < repetitions; ++rep) {
    auto t0 = Clock::now();
    for (const Cell& c : cells) sampler.sample(c.eye, c.cull, params, store);
    sampler_per_cube.push_back(seconds_since(t0) / double(cells.size()));
    t0 = Clock::now();
    for (std::size_t i = 0; i < cells.size(); ++i) trace_stream(scenes[i]->scene(), rays[i], true);
    raw_per_cube.push_back(seconds_since(t0) / double(cells.size()));
    ratios.push_back(sampler_per_cube.back() / raw_per_cube.back());
  }
  std::printf("sampler %.2f ms, raw coherent %.2f ms per cube map, alternating (medians of %d): sampler / raw %.3f "
              "(median of the per-rep ratios; range %.3f-%.3f)\n",
              1e3 * median(sampler_per_cube), 1e3 * median(raw_per_cube), repetitions, median(ratios),
              *std::min_element(ratios.begin(), ratios.end()), *std::max_element(ratios.begin(), ratios.end()));
  std::printf("peak RSS %.0f MiB\n", peak_rss_mib());
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  cellbake::keep_large_blocks_in_the_heap();  // as cellbake does
  return cellbake::run(argc, argv);
}
