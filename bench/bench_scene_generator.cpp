// Procedural scene generation speed (pipeline/scenes/scene_generator.h): generating a
// scene in memory (parts handed to a no-op callback) and writing it as binary
// PLY (pipeline/scenes/scene_ply_writer.h) to the system temp directory. Reports
// triangles per second. Run as
//   build/bench/bench_scene_generator --benchmark_filter=Ply
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "pipeline/scenes/scene_generator.h"
#include "pipeline/scenes/scene_ply_writer.h"

namespace cellbake {
namespace {

SceneParams params(benchmark::State& state) {
  SceneParams p;
  p.kind = static_cast<SceneKind>(state.range(0));
  p.target_triangles = static_cast<std::uint64_t>(state.range(1));
  return p;
}

void BM_GenerateInMemory(benchmark::State& state) {
  const SceneParams p = params(state);
  std::uint64_t triangles = 0;
  for (auto _ : state) {
    const SceneSummary s =
        generate_scene(p, [](const TriangleMesh& part) { benchmark::DoNotOptimize(part.indices.data()); });
    triangles += s.triangles;
  }
  state.counters["triangles/s"] =
      benchmark::Counter(static_cast<double>(triangles), benchmark::Counter::kIsRate);
}

void BM_GeneratePly(benchmark::State& state) {
  const SceneParams p = params(state);
  const auto out =
      std::filesystem::temp_directory_path() / ("cellbake-bench-scene-" + std::to_string(state.range(0)) +
                                                "-" + std::to_string(state.range(1)) + ".ply");
  std::uint64_t triangles = 0, bytes = 0;
  for (auto _ : state) {
    triangles += generate_scene_to_ply(p, out).triangles;
    bytes += std::filesystem::file_size(out);
  }
  std::filesystem::remove(out);
  state.counters["triangles/s"] =
      benchmark::Counter(static_cast<double>(triangles), benchmark::Counter::kIsRate);
  state.counters["bytes/s"] = benchmark::Counter(static_cast<double>(bytes), benchmark::Counter::kIsRate);
}

// kind: 0 plant, 1 house, 2 city; sizes: 2 M and the thesis power plant's 12.7 M.
BENCHMARK(BM_GenerateInMemory)
    ->ArgsProduct({{0, 1, 2}, {2'000'000, 12'700'000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_GeneratePly)
    ->ArgsProduct({{0, 1, 2}, {2'000'000, 12'700'000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace
}  // namespace cellbake

BENCHMARK_MAIN();
