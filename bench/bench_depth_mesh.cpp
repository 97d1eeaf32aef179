// Cost of build_depth_meshes for one 512^2 cube map (six faces, ~1.5 M pixels),
// in ms per cube map (the benchmark's time unit), on two analytic scenes (range
// `scene`): 0 = a closed room with boxes and pipes at several depths (no
// background, the bake's common case), 1 = an open scene from an eye far from
// the origin: a ground plane seen at grazing angles up to the horizon, a wall,
// thin pipes, and background sky (skins and background pixels). Timed without
// DepthMeshStats, as the per-cell bake calls it. Counters: triangles, skin
// edges and background pixels of the result (from one untimed call with stats).
#include <benchmark/benchmark.h>

#include "bench/bench_room_scene.h"
#include "pipeline/scenes/depth_mesh_analytic_scene.h"
#include "stages/depth_mesh.h"

namespace {

using namespace cellbake;

constexpr int kSize = 512;

CubeSample open_sample() {
  const Vec3d c{12345.6, -9876.5, 432.1};
  AnalyticScene scene;
  scene.boxes.push_back({{c.x - 1000, c.y - 1000, c.z - 2}, {c.x + 1000, c.y + 1000, c.z - 1}});  // ground
  scene.boxes.push_back({{c.x + 5, c.y - 50, c.z - 2}, {c.x + 6, c.y + 50, c.z + 20}});          // wall
  scene.boxes.push_back({{c.x - 9, c.y + 3, c.z - 2}, {c.x - 6, c.y + 8, c.z + 4}});
  for (int k = 0; k < 12; ++k)
    scene.cylinders.push_back({c.x - 8.0 + 1.7 * k, c.y - 6 + 0.9 * k, 0.05 + 0.02 * k, c.z - 2, c.z + 3.0 + k});
  return raycast_analytic_scene(scene, c + Vec3d{0.3, -0.2, 0.45}, kSize);
}

const CubeSample& sample(int scene) {
  static const CubeSample room = bench_room_sample(kSize);
  static const CubeSample open = open_sample();
  return scene == 0 ? room : open;
}

void BM_BuildDepthMeshes(benchmark::State& state) {
  const CubeSample& in = sample(int(state.range(0)));
  for (auto _ : state) {
    const auto meshes = build_depth_meshes(in, DepthMeshParams{});
    benchmark::DoNotOptimize(meshes[0].positions.data());
  }
  DepthMeshStats stats;
  build_depth_meshes(in, DepthMeshParams{}, &stats);
  state.counters["tris"] = double(stats.triangles);
  state.counters["skin_edges"] = double(stats.skin_edges);
  state.counters["background_px"] = double(stats.background_pixels);
}
BENCHMARK(BM_BuildDepthMeshes)->ArgName("scene")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
