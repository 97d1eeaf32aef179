// Speed of the incremental-TDM stages per cell, on an analytic room with
// pillars (512^2 faces, depths ray-cast exactly, tests/fixture_analytic_cube.h):
//   BM_VoidFraction/N         one best-next-view candidate scored against N samples
//                             (samples.void_resolution = 16, the bake's marching)
//   BM_RemoveRedundant/N      one delta scan reduced against N ancestors
//   BM_VoronoiCandidates/N    candidates for N samples in a 4 m square
// Run as build/bench/bench_incremental_tdm; figures go to docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <vector>

#include "stages/sample/sample_candidates.h"
#include "stages/sample/sample_redundancy.h"
#include "stages/sample/sample_void.h"
#include "tests/fixture_analytic_cube.h"

namespace cellbake {
namespace {

std::vector<test::ColoredBox> scene() {
  std::vector<test::ColoredBox> boxes = {{{{-20, -20, -0.2}, {20, 20, 0}}}, {{{-20, -20, 8}, {20, 20, 8.2}}},
                                         {{{-20.2, -20, 0}, {-20, 20, 8}}}, {{{20, -20, 0}, {20.2, 20, 8}}},
                                         {{{-20, -20.2, 0}, {20, -20, 8}}}, {{{-20, 20, 0}, {20, 20.2, 8}}}};
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j)
      if (i != 0 || j != 0) boxes.push_back({{{5.0 * i - 0.4, 5.0 * j - 0.4, 0}, {5.0 * i + 0.4, 5.0 * j + 0.4, 8}}});
  return boxes;
}

// Samples at the centre and corners (then edge midpoints) of a 4 m cell at 1.7 m.
const std::vector<CubeSample>& samples() {
  static const std::vector<CubeSample> all = [] {
    const std::vector<Vec3d> eyes = {{0, 0, 1.7},  {-2, -2, 1.7}, {2, -2, 1.7}, {-2, 2, 1.7},
                                     {2, 2, 1.7},  {0, -2, 1.7},  {-2, 0, 1.7}, {2, 0, 1.7}};
    std::vector<CubeSample> s;
    for (const Vec3d& e : eyes) s.push_back(test::analytic_colored_cube_sample(e, scene(), 512));
    return s;
  }();
  return all;
}

void BM_VoidFraction(benchmark::State& state) {
  std::vector<VoidSample> existing;
  for (int i = 0; i < state.range(0); ++i) existing.push_back({&samples()[std::size_t(i)]});
  VoidParams p;
  p.face_size = 16;
  p.step_ratio = 0.05;
  p.max_distance = 80;
  VoidResult r;
  for (auto _ : state) {
    r = void_fraction({1, 0, 1.7}, existing, p);
    benchmark::DoNotOptimize(r);
  }
  state.counters["void_fraction"] = r.fraction;
}
BENCHMARK(BM_VoidFraction)->Arg(1)->Arg(5)->Arg(8)->Unit(benchmark::kMillisecond);

void BM_RemoveRedundant(benchmark::State& state) {
  std::vector<const CubeSample*> ancestors;
  for (int i = 0; i < state.range(0); ++i) ancestors.push_back(&samples()[std::size_t(i)]);
  RedundancyStats st;
  for (auto _ : state) {
    state.PauseTiming();
    CubeSample delta = samples()[7];
    state.ResumeTiming();
    st = remove_redundant_pixels(delta, ancestors);
  }
  state.counters["removed"] = double(st.removed) / double(st.covered);
}
BENCHMARK(BM_RemoveRedundant)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

void BM_VoronoiCandidates(benchmark::State& state) {
  std::vector<Vec2d> points;
  for (int i = 0; i < state.range(0); ++i) points.push_back({-2 + 4 * ((i * 37) % 101) / 100.0, -2 + 4 * ((i * 53) % 97) / 96.0});
  std::vector<Vec2d> candidates;
  for (auto _ : state) {
    candidates = voronoi_candidates(points, {{-2, -2}, {2, 2}});
    benchmark::DoNotOptimize(candidates.data());
  }
  state.counters["candidates"] = double(candidates.size());
}
BENCHMARK(BM_VoronoiCandidates)->Arg(5)->Arg(12)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace cellbake

BENCHMARK_MAIN();
