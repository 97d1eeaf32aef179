// Cost of `cellbake merge` on synthetic shard databases of a projected size:
// S shards x C cells, each cell with one panoramic sample of six faces whose
// blobs total ~1.4 MB (random bytes: encoded images do not compress). Compares
// the ATTACH row copy used by merge_shards with a CellDb::get_cell + put_cell
// round trip through memory. Counters: cells/s and MB/s of cell blobs.
#include <benchmark/benchmark.h>

#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "runner/merge_shards.h"
#include "storage/cell_db.h"

namespace cellbake {
namespace {

constexpr std::size_t kImageBytes = 200'000, kMeshBytes = 33'000;  // per face; x6 = ~1.4 MB per cell
constexpr double kCellBytes = 6.0 * (kImageBytes + kMeshBytes);

std::vector<std::uint8_t> random_bytes(std::size_t n, std::mt19937_64& rng) {
  std::vector<std::uint8_t> out(n);
  for (std::size_t i = 0; i + 8 <= n; i += 8) {
    const std::uint64_t v = rng();
    std::memcpy(out.data() + i, &v, 8);
  }
  return out;
}

// Writes `shards` shard databases of `cells` cells each under `dir` (once per size).
std::vector<std::filesystem::path> make_shards(const std::filesystem::path& dir, int shards, int cells) {
  std::vector<std::filesystem::path> paths;
  std::mt19937_64 rng(42);
  std::int64_t id = 1;
  for (int s = 0; s < shards; ++s) {
    paths.push_back(dir / ("shard_" + std::to_string(s) + ".db"));
    if (std::filesystem::exists(paths.back())) {
      id += cells;
      continue;
    }
    CellDb db(paths.back(), CellDb::Mode::read_write);
    db.set_meta("store_hash", "synthetic");
    db.set_meta("config", "cells.size=2\n");
    db.set_meta("cells_total", std::to_string(cells));
    for (int c = 0; c < cells; ++c, ++id) {
      CellRow row;
      row.id = id;
      row.status = "done";
      row.input_hash = "in" + std::to_string(id);
      row.cull_hash = "cull" + std::to_string(id);
      row.content_hash = "content" + std::to_string(id);
      row.near_chunks = {{id, 1000, true}};
      row.stage_seconds = {{"sample", 1.0}};
      SampleRow sample;
      sample.eye = {double(id), 0, 1.6};
      for (int f = 0; f < 6; ++f)
        sample.faces.push_back({f, "jpeg", random_bytes(kImageBytes, rng), random_bytes(kMeshBytes, rng), 5000, 0, 0});
      row.samples = {std::move(sample)};
      row.bytes = std::uint64_t(kCellBytes);
      db.put_cell(row);
    }
  }
  return paths;
}

}  // namespace

// The folder holding the synthetic shards of one size (shared by the benchmarks; removed by main).
std::filesystem::path bench_dir(int shards, int cells) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("cellbake-bench-merge-" + std::to_string(shards) + "x" + std::to_string(cells));
  std::filesystem::create_directories(dir);
  return dir;
}

namespace {

void remove_db(const std::filesystem::path& db) {
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db.string() + suffix);
}

void set_counters(benchmark::State& state, int shards, int cells) {
  const double n = double(shards) * cells * state.iterations();
  state.counters["cells/s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  state.counters["MB/s"] = benchmark::Counter(n * kCellBytes / 1e6, benchmark::Counter::kIsRate);
}

// merge_shards: ATTACH + INSERT ... SELECT, one transaction per cell.
void BM_MergeShards(benchmark::State& state) {
  const int shards = int(state.range(0)), cells = int(state.range(1));
  const auto dir = bench_dir(shards, cells);
  const auto paths = make_shards(dir, shards, cells);
  const auto out = dir / "merged.db";
  for (auto _ : state) {
    state.PauseTiming();
    remove_db(out);
    state.ResumeTiming();
    merge_shards(out, paths, [](const std::string&) {});
  }
  set_counters(state, shards, cells);
  remove_db(out);
}

// The same copy through the public CellDb API: every cell decoded into memory and re-inserted.
void BM_GetPutCells(benchmark::State& state) {
  const int shards = int(state.range(0)), cells = int(state.range(1));
  const auto dir = bench_dir(shards, cells);
  const auto paths = make_shards(dir, shards, cells);
  const auto out = dir / "getput.db";
  for (auto _ : state) {
    state.PauseTiming();
    remove_db(out);
    state.ResumeTiming();
    CellDb target(out, CellDb::Mode::read_write);
    for (const auto& p : paths) {
      CellDb shard(p, CellDb::Mode::read_only);
      for (std::int64_t id : shard.cell_ids()) target.put_cell(*shard.get_cell(id));
    }
  }
  set_counters(state, shards, cells);
  remove_db(out);
}

// Re-merging shards already merged (the idempotent no-op path: hashes compared, nothing copied).
void BM_RemergeUnchanged(benchmark::State& state) {
  const int shards = int(state.range(0)), cells = int(state.range(1));
  const auto dir = bench_dir(shards, cells);
  const auto paths = make_shards(dir, shards, cells);
  const auto out = dir / "remerged.db";
  remove_db(out);
  merge_shards(out, paths, [](const std::string&) {});
  for (auto _ : state) merge_shards(out, paths, [](const std::string&) {});
  set_counters(state, shards, cells);
  remove_db(out);
}

BENCHMARK(BM_MergeShards)->Args({4, 250})->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
BENCHMARK(BM_GetPutCells)->Args({4, 250})->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
BENCHMARK(BM_RemergeUnchanged)->Args({4, 250})->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace
}  // namespace cellbake

// Runs the benchmarks, then removes the synthetic shards (gigabytes) they shared.
int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::filesystem::remove_all(cellbake::bench_dir(4, 250));
  return 0;
}
