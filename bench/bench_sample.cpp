// Panoramic sampling speed (stages/sample/sample.h): one 512^2 x 6 colour + depth cube
// map of a random scene of ~1 M triangles in 1000 chunks, rendered offscreen
// with OSMesa (llvmpipe). The project's reference figure on its 2-core machine
// is ~0.19-0.24 s per cube map with LP_NUM_THREADS=2. Run as
//   LP_NUM_THREADS=2 build/bench/bench_sample
// (the llvmpipe thread count is read from the environment; the bench sets nothing).
// Both wall time and the CPU time of the whole process (all llvmpipe threads)
// are reported: on a shared machine the latter is the steadier figure.
//
// BM_SampleStore samples real cells of a geometry store the way one bake
// worker does (one renderer and one store kept across cells, cells in order,
// cull boxes from the cull_box stage with the 100,000-triangle budget):
//   CELLBAKE_BENCH_STORE=/tmp/demo/plant.store.db and optionally
//   CELLBAKE_BENCH_EYES="18,14,1.7;22,14,1.7" LP_NUM_THREADS=1 build/bench/bench_sample
// Without CELLBAKE_BENCH_STORE it is skipped; without CELLBAKE_BENCH_EYES the
// eyes are 8 points along the model's x midline at 1/4 of its z extent.
//
// The *Embree variants run the same cube maps through the Embree ray-casting
// backend (stages/raycast/embree_cube_sampler.h, issue #12) side by side:
// warm = BVHs cached (a bake worker's steady state), cold = a fresh BVH cache
// per cube map (builds included). For medians of 5 runs pass
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_store_eyes.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/render/gl_sample_cube.h"
#include "stages/cull_box.h"
#include "stages/raycast/embree_cube_sampler.h"
#include "runner/heap_tuning.h"
#include "stages/sample/sample.h"
#include "storage/geometry_store.h"
#include "tests/fixture_chunk_source.h"

namespace cellbake {
namespace {

constexpr int kGrid = 10;                 // 10^3 chunks
constexpr int kTrianglesPerChunk = 1000;  // 1 M triangles
constexpr double kCell = 10.0;            // metres per chunk cell: a 100 m cube
const Vec3d kEye{kGrid * kCell / 2 + 0.37, kGrid * kCell / 2 - 0.21, kGrid * kCell / 2 + 0.11};
const Box3d kCullBox = Box3d::cube({kGrid * kCell / 2, kGrid * kCell / 2, kGrid * kCell / 2}, 2.0);

// Random triangles of ~0.6 m edges filling each 10 m chunk cell; one colour per
// chunk; fixed seed. Seen from the centre, chunks straddling a face edge are
// drawn in two or three faces: ~1.9 M triangles are submitted per cube map.
const test::InMemoryChunkSource& scene() {
  static const auto source = [] {
    auto s = std::make_unique<test::InMemoryChunkSource>();
    std::mt19937_64 rng(20020101);
    std::uniform_real_distribution<double> unit(0.0, 1.0), edge(-0.6, 0.6);
    std::int64_t id = 1;
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j)
        for (int k = 0; k < kGrid; ++k, ++id) {
          const Rgba8 color{static_cast<std::uint8_t>(rng() % 256), static_cast<std::uint8_t>(rng() % 256),
                            static_cast<std::uint8_t>(rng() % 256), 255};
          std::vector<Triangle> triangles;
          triangles.reserve(kTrianglesPerChunk);
          for (int t = 0; t < kTrianglesPerChunk; ++t) {
            const Vec3d a{(i + unit(rng)) * kCell, (j + unit(rng)) * kCell, (k + unit(rng)) * kCell};
            triangles.push_back(test::flat_triangle(a, a + Vec3d{edge(rng), edge(rng), edge(rng)},
                                                    a + Vec3d{edge(rng), edge(rng), edge(rng)}, color));
          }
          s->add(test::chunk_from_triangles(id, triangles));
        }
    return s;
  }();
  return *source;
}

std::unique_ptr<ChunkRenderer> make_renderer() {
  return std::make_unique<ChunkRenderer>(create_gl_context(GlBackend::osmesa, 1, 1));
}

void report(benchmark::State& state, const ChunkRenderer& renderer, std::uint64_t triangles_before) {
  const double cube_maps = static_cast<double>(state.iterations());
  state.counters["tris_drawn_per_cube"] =
      static_cast<double>(renderer.stats().triangles_drawn - triangles_before) / cube_maps;
  state.counters["reversed_z"] = renderer.reversed_z() ? 1 : 0;
}

// Chunks already cached in the renderer (the steady state of a worker thread).
void BM_SampleCubeWarm(benchmark::State& state) {
  const auto& source = scene();
  SampleParams params;
  params.face_size = static_cast<int>(state.range(0));
  params.supersample = static_cast<int>(state.range(1));
  auto renderer = make_renderer();
  sample_cube(kEye, kCullBox, params, source, *renderer);  // upload everything once
  const std::uint64_t before = renderer->stats().triangles_drawn;
  for (auto _ : state) benchmark::DoNotOptimize(sample_cube(kEye, kCullBox, params, source, *renderer));
  report(state, *renderer, before);
}
// 512/1: the thesis' stored resolution; 512/2: rendered at 1024^2 and box-filtered
// down; 64/1: the same draws at a tiny resolution, i.e. the geometry front end
// (vertex work, clipping, binning) with almost no rasterisation.
BENCHMARK(BM_SampleCubeWarm)->Args({512, 1})->Args({512, 2})->Args({64, 1})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// A fresh renderer per cube map: uploads of every visible chunk included
// (context creation and shader compilation excluded).
void BM_SampleCubeCold(benchmark::State& state) {
  const auto& source = scene();
  SampleParams params;
  params.face_size = static_cast<int>(state.range(0));
  std::uint64_t triangles = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto renderer = make_renderer();
    state.ResumeTiming();
    benchmark::DoNotOptimize(sample_cube(kEye, kCullBox, params, source, *renderer));
    triangles += renderer->stats().triangles_drawn;
    state.PauseTiming();
    renderer.reset();
    state.ResumeTiming();
  }
  state.counters["tris_drawn_per_cube"] = static_cast<double>(triangles) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_SampleCubeCold)->Arg(512)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

std::unique_ptr<EmbreeCubeSampler> make_embree(ChunkBvhCacheParams params = {}) {
  return std::make_unique<EmbreeCubeSampler>(std::make_shared<ChunkBvhCache>(params));
}

void report_embree(benchmark::State& state, const EmbreeCubeSampler& sampler, const EmbreeSamplerStats& before) {
  const EmbreeSamplerStats& s = sampler.stats();
  const double cube_maps = static_cast<double>(s.cube_maps - before.cube_maps);
  state.counters["instances_per_cube"] = static_cast<double>(s.instances - before.instances) / cube_maps;
  state.counters["gather_ms_per_cube"] = 1e3 * (s.gather_seconds - before.gather_seconds) / cube_maps;
  state.counters["scene_ms_per_cube"] = 1e3 * (s.scene_seconds - before.scene_seconds) / cube_maps;
  state.counters["trace_ms_per_cube"] = 1e3 * (s.trace_seconds - before.trace_seconds) / cube_maps;
  state.counters["bvh_device_MiB"] = static_cast<double>(sampler.cache().stats().device_bytes) / 1048576.0;
}

void BM_SampleCubeWarmEmbree(benchmark::State& state) {
  const auto& source = scene();
  SampleParams params;
  params.face_size = static_cast<int>(state.range(0));
  params.supersample = static_cast<int>(state.range(1));
  auto sampler = make_embree();
  sampler->sample(kEye, kCullBox, params, source);  // build every BVH once
  const EmbreeSamplerStats before = sampler->stats();
  for (auto _ : state) benchmark::DoNotOptimize(sampler->sample(kEye, kCullBox, params, source));
  report_embree(state, *sampler, before);
}
BENCHMARK(BM_SampleCubeWarmEmbree)->Args({512, 1})->Args({512, 2})->Args({64, 1})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// A fresh BVH cache per cube map: every chunk BVH built (Embree may build on
// several threads; the CPU time counts them all).
void BM_SampleCubeColdEmbree(benchmark::State& state) {
  const auto& source = scene();
  SampleParams params;
  params.face_size = static_cast<int>(state.range(0));
  std::uint64_t triangles = 0;
  for (auto _ : state) {
    auto sampler = make_embree();
    benchmark::DoNotOptimize(sampler->sample(kEye, kCullBox, params, source));
    triangles += sampler->cache().stats().triangles_built;
    state.PauseTiming();
    sampler.reset();
    state.ResumeTiming();
  }
  state.counters["tris_built_per_cube"] = static_cast<double>(triangles) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_SampleCubeColdEmbree)->Arg(512)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// The store's cells with their cull boxes (as bench_raycast_raw uses them too).
std::vector<std::pair<Vec3d, Box3d>> store_cells(const GeometryStore& store) {
  std::vector<std::pair<Vec3d, Box3d>> cells;
  for (const Vec3d& eye : bench_eyes(store.model_bounds())) {
    CullBoxParams cull;
    cull.min_half_size = 2.0;  // 4 m cells, as in configs/plant-demo.toml
    cells.emplace_back(eye, Box3d::cube(eye, find_cull_box(eye, cull, store).half_size));
  }
  return cells;
}

void BM_SampleStoreEmbree(benchmark::State& state) {
  const char* path = std::getenv("CELLBAKE_BENCH_STORE");
  if (!path) {
    state.SkipWithError("CELLBAKE_BENCH_STORE is not set");
    return;
  }
  const GeometryStore store(path);
  const auto cells = store_cells(store);
  SampleParams params;
  params.face_size = static_cast<int>(state.range(0));
  ChunkBvhCacheParams cache_params;
  cache_params.group_triangles = static_cast<std::size_t>(state.range(1));  // 0: the bake's default
  auto sampler = make_embree(cache_params);
  for (const auto& [eye, cull_box] : cells) sampler->sample(eye, cull_box, params, store);  // build BVHs
  const EmbreeSamplerStats before = sampler->stats();
  for (auto _ : state)
    for (const auto& [eye, cull_box] : cells) benchmark::DoNotOptimize(sampler->sample(eye, cull_box, params, store));
  state.counters["cells"] = static_cast<double>(cells.size());
  report_embree(state, *sampler, before);
}
// Args: face size, triangles per chunk group (0: the default, one group when
// the model fits one batch; 1 << 20 was the default before 2026-12-03).
BENCHMARK(BM_SampleStoreEmbree)
    ->Args({512, 0})
    ->Args({512, 1 << 20})
    ->Args({128, 0})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(2);

void BM_SampleStore(benchmark::State& state) {
  const char* path = std::getenv("CELLBAKE_BENCH_STORE");
  if (!path) {
    state.SkipWithError("CELLBAKE_BENCH_STORE is not set");
    return;
  }
  const GeometryStore store(path);
  const auto cells = store_cells(store);
  SampleParams params;
  params.face_size = static_cast<int>(state.range(0));
  auto renderer = make_renderer();
  for (const auto& [eye, cull_box] : cells) sample_cube(eye, cull_box, params, store, *renderer);  // warm caches
  const ChunkRendererStats before = renderer->stats();
  for (auto _ : state)
    for (const auto& [eye, cull_box] : cells) benchmark::DoNotOptimize(sample_cube(eye, cull_box, params, store, *renderer));
  const double cube_maps = static_cast<double>(state.iterations() * cells.size());
  const ChunkRendererStats stats = renderer->stats();
  state.counters["cells"] = static_cast<double>(cells.size());
  state.counters["tris_drawn_per_cube"] = static_cast<double>(stats.triangles_drawn - before.triangles_drawn) / cube_maps;
  state.counters["uploads_per_cube"] = static_cast<double>(stats.uploads - before.uploads) / cube_maps;
  state.counters["occluded_per_cube"] = static_cast<double>(stats.chunks_occluded - before.chunks_occluded) / cube_maps;
  state.counters["drawn_per_cube"] = static_cast<double>(stats.chunks_drawn - before.chunks_drawn) / cube_maps;
}
// After one untimed pass over the cells (caches warm, as on a worker that has
// baked a few neighbours), times passes over all cells; divide by the `cells` counter for one cube map.
BENCHMARK(BM_SampleStore)->Arg(512)->Arg(128)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(2);

}  // namespace
}  // namespace cellbake

// Google Benchmark's main, with the bake's allocator settings.
int main(int argc, char** argv) {
  cellbake::keep_large_blocks_in_the_heap();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
