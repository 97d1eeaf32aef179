// EGL vs OSMesa (issue #12): the same 512^2 x 6 cube maps of real cells of a
// geometry store through the sample stage (stages/sample.h), once per GL
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
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>
#include <utility>
#include <vector>

#include "bench/bench_store_eyes.h"
#include "stages/cull_box.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "stages/sample.h"
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

void BM_CubeMapStore(benchmark::State& state) {
  const GlBackend backend = backend_of(state);
  const char* path = std::getenv("CELLBAKE_BENCH_STORE");
  if (!path) {
    state.SkipWithError("CELLBAKE_BENCH_STORE is not set");
    return;
  }
  if (!gl_backend_compiled(backend)) {
    state.SkipWithError("backend not in this build");
    return;
  }
  const GeometryStore store(path);
  std::vector<std::pair<Vec3d, Box3d>> cells;
  for (const Vec3d& eye : bench_eyes(store.model_bounds())) {
    CullBoxParams cull;
    cull.min_half_size = 2.0;  // 4 m cells, as in configs/plant-demo.toml
    cells.emplace_back(eye, Box3d::cube(eye, find_cull_box(eye, cull, store).half_size));
  }
  SampleParams params;
  params.face_size = 512;
  ChunkRenderer renderer(create_gl_context(backend, 1, 1));
  for (const auto& [eye, cull_box] : cells) sample_cube(eye, cull_box, params, store, renderer);  // warm caches
  const ChunkRendererStats before = renderer.stats();
  for (auto _ : state)
    for (const auto& [eye, cull_box] : cells) benchmark::DoNotOptimize(sample_cube(eye, cull_box, params, store, renderer));
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

}  // namespace
}  // namespace cellbake

BENCHMARK_MAIN();
