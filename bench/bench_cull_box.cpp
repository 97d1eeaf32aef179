// Cull-box search time per cell on a procedural 12.7 M-triangle plant held in
// memory (chunks of 3,520 triangles: dense pipe clusters plus sparse floor and
// wall plates), budget 100,000 triangles; and bytes + encode/decode time of a
// 512 x 512 cube face as JPEG / WebP / PNG.
//   cmake -DCELLBAKE_BUILD_BENCH=ON ... && ninja bench_cull_box && ./bench/bench_cull_box
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <random>
#include <vector>

#include "bench/bench_store_eyes.h"
#include "stages/cull_box.h"
#include "stages/encode/encode.h"
#include "storage/geometry_store.h"
#include "tests/fixture_memory_chunk_source.h"

namespace cellbake {
namespace {

constexpr int kSides = 16, kRings = 111;   // 16 * 110 * 2 = 3520 triangles per pipe chunk
constexpr int kPlateX = 40, kPlateY = 44;  // 40 * 44 * 2 = 3520 triangles per plate chunk

// A pipe segment of radius r from `start` along axis `axis` for `length`.
Chunk pipe_chunk(std::int64_t id, const Vec3d& start, int axis, double radius, double length) {
  Chunk c;
  c.id = id;
  c.origin = start;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  for (int ring = 0; ring < kRings; ++ring)
    for (int s = 0; s < kSides; ++s) {
      const double a = 2 * M_PI * s / kSides;
      double p[3];
      p[axis] = length * ring / (kRings - 1);
      p[u] = radius * std::cos(a);
      p[v] = radius * std::sin(a);
      c.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
      c.colors.push_back({120, 130, 140, 255});
    }
  for (std::uint32_t ring = 0; ring + 1 < kRings; ++ring)
    for (std::uint32_t s = 0; s < kSides; ++s) {
      const std::uint32_t a = ring * kSides + s, b = ring * kSides + (s + 1) % kSides, d = a + kSides,
                          e = b + kSides;
      c.indices.insert(c.indices.end(), {a, b, d, b, e, d});
    }
  test::compute_memory_chunk_bounds(c);
  return c;
}

// A flat plate spanning `size` along axes u and v (normal axis n), origin at `corner`.
Chunk plate_chunk(std::int64_t id, const Vec3d& corner, int n, double su, double sv) {
  Chunk c;
  c.id = id;
  c.origin = corner;
  const int u = (n + 1) % 3, v = (n + 2) % 3;
  for (int j = 0; j <= kPlateY; ++j)
    for (int i = 0; i <= kPlateX; ++i) {
      double p[3] = {0, 0, 0};
      p[u] = su * i / kPlateX;
      p[v] = sv * j / kPlateY;
      c.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
      c.colors.push_back({180, 180, 170, 255});
    }
  for (std::uint32_t j = 0; j < kPlateY; ++j)
    for (std::uint32_t i = 0; i < kPlateX; ++i) {
      const std::uint32_t a = j * (kPlateX + 1) + i, b = a + 1, d = a + kPlateX + 1, e = d + 1;
      c.indices.insert(c.indices.end(), {a, b, d, b, e, d});
    }
  test::compute_memory_chunk_bounds(c);
  return c;
}

struct PlantScene {
  test::MemoryChunkSource source;
  std::uint64_t triangles = 0;
  std::vector<Vec3d> cells;  // cell centres to time
};

// 160 x 160 x 40 m hall; 2,900 pipe chunks in 10 clusters of 6-14 m, 730 plates
// spread out (floors every 8 m, walls). Fixed seed.
const PlantScene& plant_scene() {
  static const std::unique_ptr<PlantScene> scene = [] {
    auto owned = std::make_unique<PlantScene>();
    PlantScene& s = *owned;
    std::mt19937_64 rng(2002);
    std::uniform_real_distribution<double> unit(0, 1);
    std::int64_t id = 1;
    struct Cluster {
      Vec3d lo;
      double size;
    };
    std::vector<Cluster> clusters;
    for (int k = 0; k < 10; ++k)
      clusters.push_back(
          {{10 + 130 * unit(rng), 10 + 130 * unit(rng), 2 + 20 * unit(rng)}, 6 + 8 * unit(rng)});
    for (int i = 0; i < 2900; ++i) {
      const Cluster& cl = clusters[i % clusters.size()];
      const int axis = static_cast<int>(rng() % 3);
      const double length = std::min(2.0, cl.size);
      Vec3d start{cl.lo.x + cl.size * unit(rng), cl.lo.y + cl.size * unit(rng),
                  cl.lo.z + cl.size * unit(rng)};
      start[axis] = cl.lo[axis] + (cl.size - length) * unit(rng);
      s.source.add(pipe_chunk(id++, start, axis, 0.03 + 0.2 * unit(rng), length));
    }
    for (int i = 0; i < 730; ++i) {
      const int n = i % 4 == 0 ? static_cast<int>(rng() % 2) : 2;  // mostly floors, some walls
      Vec3d corner{150 * unit(rng), 150 * unit(rng),
                   n == 2 ? 8.0 * static_cast<int>(rng() % 5) : 32 * unit(rng)};
      s.source.add(plate_chunk(id++, corner, n, 8, 8));
    }
    s.triangles = 3520ull * (2900 + 730);
    // Half the cells inside clusters, half anywhere in the hall.
    for (int i = 0; i < 64; ++i) {
      if (i % 2 == 0) {
        const Cluster& cl = clusters[(i / 2) % clusters.size()];
        s.cells.push_back(
            {cl.lo.x + cl.size * unit(rng), cl.lo.y + cl.size * unit(rng), cl.lo.z + cl.size * unit(rng)});
      } else {
        s.cells.push_back({160 * unit(rng), 160 * unit(rng), 1 + 38 * unit(rng)});
      }
    }
    return owned;
  }();
  return *scene;
}

void BM_CullBoxPerCell(benchmark::State& state) {
  const PlantScene& scene = plant_scene();
  CullBoxParams params;
  params.triangle_budget = 100000;
  params.min_half_size = 0.5;
  std::size_t next = 0;
  double half_sum = 0, loaded_sum = 0, triangles_sum = 0;
  std::int64_t cells = 0;
  for (auto _ : state) {
    const CullBoxResult r = find_cull_box(scene.cells[next], params, scene.source);
    next = (next + 1) % scene.cells.size();
    half_sum += r.half_size;
    loaded_sum += static_cast<double>(r.chunks_loaded);
    triangles_sum += static_cast<double>(r.triangle_count);
    ++cells;
    benchmark::DoNotOptimize(r);
  }
  state.counters["scene_triangles"] = static_cast<double>(scene.triangles);
  state.counters["mean_half_size_m"] = half_sum / cells;
  state.counters["mean_chunks_loaded"] = loaded_sum / cells;
  state.counters["mean_near_triangles"] = triangles_sum / cells;
  state.SetItemsProcessed(cells);
}
BENCHMARK(BM_CullBoxPerCell)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The same search on a real geometry store (CELLBAKE_BENCH_STORE; eyes from
// CELLBAKE_BENCH_EYES, see bench_store_eyes.h), 4 m cells, budget 100 k.
// Arg 1: warm (one store for all passes, its chunk cache filled by an untimed
// pass, as on a worker that baked neighbours); arg 0: cold (a fresh store per
// pass: every chunk the search cuts is read and decoded).
void BM_CullBoxStore(benchmark::State& state) {
  const char* path = std::getenv("CELLBAKE_BENCH_STORE");
  if (!path) {
    state.SkipWithError("CELLBAKE_BENCH_STORE is not set");
    return;
  }
  const bool warm = state.range(0) != 0;
  auto store = std::make_unique<GeometryStore>(path);
  const std::vector<Vec3d> eyes = bench_eyes(store->model_bounds());
  CullBoxParams params;
  params.triangle_budget = 100000;
  params.min_half_size = 2.0;
  if (warm)
    for (const Vec3d& eye : eyes) find_cull_box(eye, params, *store);
  double loaded = 0, queried = 0;
  for (auto _ : state) {
    if (!warm) {
      state.PauseTiming();
      store = std::make_unique<GeometryStore>(path);
      state.ResumeTiming();
    }
    for (const Vec3d& eye : eyes) {
      const CullBoxResult r = find_cull_box(eye, params, *store);
      loaded += static_cast<double>(r.chunks_loaded);
      queried += static_cast<double>(r.chunks_queried);
    }
  }
  const double cells = static_cast<double>(state.iterations() * eyes.size());
  state.counters["cells"] = static_cast<double>(eyes.size());
  state.counters["ms_per_cell"] = benchmark::Counter(cells / 1e3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["chunks_loaded_per_cell"] = loaded / cells;
  state.counters["chunks_queried_per_cell"] = queried / cells;
}
BENCHMARK(BM_CullBoxStore)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime()->Iterations(3);

// A 512 x 512 face that looks like a render: shaded gradients, hard edges, sky.
std::vector<Rgba8> face_image() {
  std::vector<Rgba8> px(512 * 512);
  for (int y = 0; y < 512; ++y)
    for (int x = 0; x < 512; ++x) {
      Rgba8& p = px[y * 512 + x];
      const bool pipe = ((x / 37) % 3 == 0) || (std::abs((x + 2 * y) % 97 - 48) < 6);
      const double shade = 0.5 + 0.5 * std::sin(x * 0.17) * std::cos(y * 0.05);
      if (y < 80 && !pipe) {
        p = {150, 190, 235, 255};
      } else if (pipe) {
        p = {static_cast<std::uint8_t>(90 + 100 * shade), static_cast<std::uint8_t>(95 + 90 * shade),
             static_cast<std::uint8_t>(110 + 80 * shade), 255};
      } else {
        p = {static_cast<std::uint8_t>(160 + 40 * shade), 150, static_cast<std::uint8_t>(120 + (x ^ y) % 16),
             255};
      }
    }
  return px;
}

void BM_EncodeFace(benchmark::State& state, const char* format) {
  const auto px = face_image();
  std::size_t bytes = 0;
  for (auto _ : state) {
    const auto out = encode_image(px, 512, 512, {format, 85});
    bytes = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["bytes"] = static_cast<double>(bytes);
}
BENCHMARK_CAPTURE(BM_EncodeFace, jpeg, "jpeg")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_EncodeFace, webp, "webp")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_EncodeFace, png, "png")->Unit(benchmark::kMillisecond);

void BM_DecodeFace(benchmark::State& state, const char* format) {
  const auto bytes = encode_image(face_image(), 512, 512, {format, 85});
  for (auto _ : state) {
    const DecodedImage img = decode_image(bytes);
    benchmark::DoNotOptimize(img.pixels.data());
  }
  state.counters["bytes"] = static_cast<double>(bytes.size());
}
BENCHMARK_CAPTURE(BM_DecodeFace, jpeg, "jpeg")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DecodeFace, webp, "webp")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DecodeFace, png, "png")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace cellbake

BENCHMARK_MAIN();
