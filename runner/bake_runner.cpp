#include "runner/bake_runner.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/flow_graph.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <thread>

#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"
#include "pipeline/sample_backend.h"
#include "runner/parallel.h"
#include "runner/progress.h"
#include "runner/shards.h"
#include "stages/sample/cube_sampler.h"
#include "stages/raycast/chunk_bvh_cache.h"
#include "stages/tsan_handoff.h"
#include "storage/cell_db.h"
#include "storage/cell_db_lock.h"
#include "storage/geometry_store.h"
#include "storage/store_check.h"

namespace cellbake {
namespace {

// One line on the Embree backend's work in a bake (bake -v): BVH builds, the
// cache's peak, and how cube maps beyond half the cap were split.
std::string describe_embree_work(const ChunkBvhCacheStats& cache, const CubeSamplerWork& s) {
  char line[512];
  std::snprintf(line, sizeof line,
                "embree: %llu cube maps in %llu batches (%llu groups skipped, hidden); %llu BVH builds of %zu groups, "
                "%.1f M triangles in %.1f thread-s (%.1f s loading chunks); peak device memory %.0f MiB",
                (unsigned long long)s.cube_maps, (unsigned long long)s.batches, (unsigned long long)s.groups_hidden,
                (unsigned long long)cache.builds, cache.groups, double(cache.triangles_built) / 1e6, cache.build_seconds,
                cache.load_seconds, double(cache.peak_device_bytes) / double(1 << 20));
  return line;
}

// TSan tokens (stages/tsan_handoff.h) at fixed addresses, since a node body
// reads them before it has acquired anything: the graph's start happens before
// every node body, a cell's previous stage before its next one (the cell's
// CellWork is its token), one write before the next (a serial node), and every
// body before wait_for_all returns.
const char graph_start = 0, graph_done = 0, writes = 0;

// "cell 12 done in 3.42 s (cull_box 0.10, sample 2.90, ..., encode 0.05 s, of which void 0.40, redundancy
// 0.02): 3 samples, 1200 near + 5400 far triangles, 45.6 KB": the stages in order, then the timings
// measured inside them (sample's void search, depth_mesh's redundancy removal).
std::string describe_cell_row(const CellRow& row) {
  std::string stages, within;
  double total = 0;
  std::map<std::string, double> left = row.stage_seconds;
  const auto add = [](std::string& list, const std::string& name, double s) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s%s %.2f", list.empty() ? "" : ", ", name.c_str(), s);
    list += buf;
  };
  for (const char* name : kStageNames)
    if (const auto it = left.find(name); it != left.end()) {
      add(stages, it->first, it->second);
      total += it->second;
      left.erase(it);
    }
  for (const auto& [name, s] : left) add(within, name, s);
  char buf[640];
  std::snprintf(buf, sizeof buf, "cell %lld %s in %.2f s (%s s%s%s): %zu samples, %llu near + %llu far triangles, %.1f KB",
                (long long)row.id, row.status.c_str(), total, stages.c_str(), within.empty() ? "" : ", of which ",
                within.c_str(), row.samples.size(), (unsigned long long)row.near_triangles,
                (unsigned long long)(row.far_triangles + row.far_geometry_triangles), row.bytes / 1e3);
  return buf;
}

}  // namespace

BakePlan plan_bake(const BakeConfig& given, const BakeOptions& options, const GeometryStore& store) {
  BakePlan plan;
  plan.config = given;
  BakeConfig& config = plan.config;
  validate_bake_config(config);
  plan.up_note = resolve_up_axis(config, store.summary().up, store.summary().up_source);
  if (!config.floors.empty()) {  // before any cell id is given: ids follow the regions' order
    plan.floors = find_floor_regions(store, config, store.path().string());
    config.regions.clear();
    for (const FloorRegion& r : plan.floors.regions) config.regions.push_back(r.region);
    config.floors = {};
  }
  check_regions_meet_model(config.regions, store.model_bounds(), config.cell_size);
  plan.model_triangles = store.summary().triangles;
  config.near_budget = effective_near_budget(config, plan.model_triangles);
  const std::vector<CellSpec> all_cells = enumerate_cells(config.regions, config.cell_size);
  plan.cells_total = all_cells.size();
  plan.cells = select_cells(all_cells, options.cells);
  if (options.shard_count > 1) plan.cells = shard_cells(plan.cells, options.shard_index, options.shard_count, store);
  return plan;
}

namespace {

// The plan's notes on stderr: the up-axis note (even with --quiet: it changes
// the bake), the floors' eye heights, and a model that fits the near budget whole.
void print_plan_notes(const BakePlan& plan, const BakeOptions& options) {
  const BakeConfig& config = plan.config;
  if (!plan.up_note.empty()) std::fprintf(stderr, "%s\n", plan.up_note.c_str());
  if (!options.quiet && !plan.floors.regions.empty()) {
    std::string eyes;
    int last = -1;
    for (const FloorRegion& r : plan.floors.regions) {
      if (r.floor == last) continue;  // the same floor over another footprint
      last = r.floor;
      char buf[96];
      std::snprintf(buf, sizeof buf, "%sfloor %d: eyes at %s = %g", eyes.empty() ? "" : ", ", r.floor,
                    config.up.c_str(), r.eye);
      eyes += buf;
    }
    std::fprintf(stderr, "floors as regions (%g above each): %s\n", plan.floors.eye_height, eyes.c_str());
    for (const std::string& note : plan.floors.notes) std::fprintf(stderr, "note: %s\n", note.c_str());
  }
  if (plan.model_triangles <= config.near_budget && !options.quiet)
    std::fprintf(stderr,
                 "note: the whole model (%llu triangles) fits the near-field budget (%llu): cells draw it as "
                 "geometry and have no far field\n",
                 (unsigned long long)plan.model_triangles, (unsigned long long)config.near_budget);
}

// The database's meta rows for this bake (store, its hash, config, up axis,
// cell size, cell counts), after a note when it was baked from another store.
void record_bake_meta(CellDb& db, const BakePlan& plan, const std::string& store_hash) {
  const BakeConfig& config = plan.config;
  if (auto existing = db.meta("store_hash"); existing && *existing != store_hash)
    std::fprintf(stderr, "note: %s was baked from a different geometry store; affected cells will be recomputed\n",
                 config.database.c_str());
  db.set_meta("store", std::filesystem::absolute(config.store).string());
  db.set_meta("store_hash", store_hash);
  db.set_meta("config", describe_bake_config(config));
  db.set_meta("up", config.up);
  db.set_meta("cell_size", std::to_string(config.cell_size));
  // The configuration's cell count, not this run's selection: `status` counts
  // what --cells or the other shards left out as pending.
  db.set_meta("cells_total", std::to_string(plan.cells_total));
  db.set_meta("cells_selected", std::to_string(plan.cells.size()));  // this run's (shard's) cells, for merge
}

// The cells to bake, each with its hashes. Unless `force`, a cell whose stored
// row is done with the same input hash is skipped (counted up to date), and one
// with the same cull hash reuses its stored cull box (counted).
std::vector<std::unique_ptr<CellWork>> queue_cells(const std::vector<CellSpec>& cells, const BakeConfig& config,
                                                   const std::string& store_hash, const CellDb& db, bool force,
                                                   BakeSummary& summary) {
  const auto stamps = db.stamps();
  std::vector<std::unique_ptr<CellWork>> queued;  // owns every cell the graph passes along
  for (const auto& c : cells) {
    auto work = std::make_unique<CellWork>();
    work->cell = c;
    work->hashes = cell_hashes(c, config, store_hash);
    auto it = stamps.find(c.id);
    if (it != stamps.end() && !force && it->second.status == "done" && it->second.error.empty()) {
      if (it->second.input_hash == work->hashes.input) {
        ++summary.cells_up_to_date;
        continue;
      }
      if (it->second.cull_hash == work->hashes.cull) {
        CullBoxResult r;
        r.half_size = it->second.cull_half_size;
        r.triangle_count = it->second.near_triangles;
        for (const auto& n : it->second.near_chunks) r.near_field.push_back({n.chunk_id, n.triangles, n.whole});
        work->cull = r;
        ++summary.cull_reused;
      }
    }
    queued.push_back(std::move(work));
  }
  return queued;
}

// The graph passes plain pointers into the queued cells, which outlive it. TBB
// copies messages into tasks that other threads may steal, unseen by TSan:
// a plain pointer's copies are TBB's own accesses (tests/sanitizers/tsan.supp),
// a shared_ptr's would be libstdc++'s, reported as races in CI's tsan job.
using WorkPtr = CellWork*;
using ThreadSamplers = tbb::enumerable_thread_specific<std::unique_ptr<CubeSampler>>;

// What the graph's node bodies share: the bake's inputs, the workers'
// samplers, and where written cells are counted and reported.
struct CellGraphContext {
  const BakeConfig& config;
  const BakeOptions& options;
  const GeometryStore& store;
  CellDb& db;
  const CubeSamplerFactory& samplers;  // one sampler per worker thread, made on first use
  ThreadSamplers& thread_samplers;
  ProgressBar& progress;
  BakeSummary& summary;
  std::uint64_t done = 0;  // cells written so far (by the serial writer)
};

// Node body: stage cull_box.
WorkPtr cull_cell(CellGraphContext& ctx, WorkPtr w) {
  run_stage(*w, "cull_box", [&] { run_cull_box(*w, ctx.config, ctx.store); });
  return w;
}

// Node body: stage sample, on this worker thread's own sampler.
WorkPtr sample_cell(CellGraphContext& ctx, WorkPtr w) {
  run_stage(*w, "sample", [&] {
    auto& sampler = ctx.thread_samplers.local();
    if (!sampler) sampler = ctx.samplers.make();
    try {
      run_sample(*w, ctx.config, ctx.store, *sampler);
    } catch (...) {
      sampler->end_work();
      throw;
    }
    sampler->end_work();  // samplers are destroyed on another thread
  });
  return w;
}

// Node body: stages depth_mesh, far_choice and encode.
WorkPtr mesh_cell(CellGraphContext& ctx, WorkPtr w) {
  run_stage(*w, "depth_mesh", [&] { run_sample_tree(*w, ctx.config); });
  run_stage(*w, "far_choice", [&] { run_far_choice(*w, ctx.config, ctx.store); });
  run_stage(*w, "encode", [&] { run_encode(*w, ctx.config); });
  return w;
}

// Node body of the serial writer: the cell's row committed and counted, its
// error (or with --verbose its summary) printed, its memory freed.
tbb::flow::continue_msg write_cell(CellGraphContext& ctx, WorkPtr w) {
  tsan::after(&writes);
  const CellRow row = finish_cell_row(*w);
  ctx.db.put_cell(row);
  if (row.status == "done") {
    ++ctx.summary.cells_baked;
    ctx.summary.cells_without_far_field += row.far_triangles == 0 && row.far_geometry_triangles == 0;
  } else {
    ++ctx.summary.cells_failed;
    ctx.progress.line(row.error);
  }
  if (ctx.options.verbose) ctx.progress.line(describe_cell_row(row));
  *w = CellWork{};  // free memory now; the pointer may linger in the graph
  if (!ctx.options.quiet) ctx.progress.update(++ctx.done);
  tsan::before(&writes);
  return tbb::flow::continue_msg{};
}

// Runs the queued cells through the flow graph (bake_runner.h), at most
// 2 * threads cells in flight, and returns when every cell is written.
void run_cell_graph(const std::vector<std::unique_ptr<CellWork>>& queued, int threads, CellGraphContext& ctx) {
  std::atomic<std::size_t> next{0};
  tbb::flow::graph g;
  // A node body as TBB runs it, with the hand-offs TSan cannot see marked.
  const auto stage = [&](auto body) {
    return [&, body](WorkPtr w) {
      tsan::after(&graph_start);
      tsan::after(w);
      auto out = body(ctx, w);
      tsan::before(w);
      tsan::before(&graph_done);
      return out;
    };
  };
  tbb::flow::input_node<WorkPtr> source(g, [&](tbb::flow_control& fc) -> WorkPtr {
    tsan::after(&graph_start);
    const std::size_t i = next++;
    tsan::before(&graph_done);
    if (i >= queued.size()) {
      fc.stop();
      return {};
    }
    return queued[i].get();
  });
  // Bound the cells in flight (each holds a cube map and dense meshes).
  tbb::flow::limiter_node<WorkPtr> limiter(g, std::size_t(2 * threads));
  tbb::flow::function_node<WorkPtr, WorkPtr> cull(g, tbb::flow::unlimited, stage(cull_cell));
  tbb::flow::function_node<WorkPtr, WorkPtr> sample(g, std::size_t(threads), stage(sample_cell));
  tbb::flow::function_node<WorkPtr, WorkPtr> mesh(g, tbb::flow::unlimited, stage(mesh_cell));
  tbb::flow::function_node<WorkPtr, tbb::flow::continue_msg> write(g, tbb::flow::serial, stage(write_cell));
  tbb::flow::make_edge(source, limiter);
  tbb::flow::make_edge(limiter, cull);
  tbb::flow::make_edge(cull, sample);
  tbb::flow::make_edge(sample, mesh);
  tbb::flow::make_edge(mesh, write);
  tbb::flow::make_edge(write, limiter.decrementer());
  tsan::before(&graph_start);
  source.activate();
  g.wait_for_all();
  tsan::after(&graph_done);
#ifdef CELLBAKE_TSAN
  // Every graph task ends by decrementing the graph's wait count (in TBB's
  // headers, so TSan sees it); one more decrement here orders what TBB did
  // after our bodies (its buffers, the input node's item) before the nodes'
  // destruction below.
  g.reserve_wait();
  g.release_wait();
#endif
}

// Who sampled (the first worker sampler's backend and device, into the
// summary) and, with --verbose, the Embree backend's work in one line.
void report_sampler_work(CellGraphContext& ctx) {
  for (const auto& sampler : ctx.thread_samplers)
    if (sampler) {
      ctx.summary.sample_backend = sampler->backend_name();
      ctx.summary.sample_device = sampler->device();
      break;
    }
  if (ctx.options.verbose && ctx.samplers.bvh_cache()) {
    CubeSamplerWork total;
    for (const auto& sampler : ctx.thread_samplers)
      if (sampler) total += sampler->work();
    if (total.cube_maps > 0) ctx.progress.line(describe_embree_work(ctx.samplers.bvh_cache()->stats(), total));
  }
}

// Bakes the queued cells on `threads` worker threads, each with its own sampler
// (the Embree backend's BVH cache is shared by all of them).
void bake_queued_cells(const std::vector<std::unique_ptr<CellWork>>& queued, int threads, const BakeConfig& config,
                       const BakeOptions& options, const GeometryStore& store, CellDb& db, ProgressBar& progress,
                       BakeSummary& summary) {
  tbb::task_arena arena(threads);
  arena.execute([&] {
    const CubeSamplerFactory samplers(parse_sample_backend(config.sample_backend),
                                      std::size_t(config.embree_cache_mb) << 20,
                                      std::size_t(config.texture_cache_mb) << 20);
    if (!options.quiet && parse_sample_backend(config.sample_backend) == SampleBackend::automatic &&
        !automatic_backend_note().empty())
      progress.line("note: " + automatic_backend_note());
    ThreadSamplers thread_samplers;
    CellGraphContext ctx{config, options, store, db, samplers, thread_samplers, progress, summary};
    run_cell_graph(queued, threads, ctx);
    report_sampler_work(ctx);
  });
}

// A model larger than the budget with no far field in any baked cell: its
// chunks are too coarse (a cell's near field is every chunk reaching into its
// cull box). A note suggests ingesting it again with smaller chunks.
void note_chunks_too_coarse(const BakeSummary& summary, const BakePlan& plan, const GeometryStore& store,
                            const BakeOptions& options) {
  const BakeConfig& config = plan.config;
  const std::uint64_t model_triangles = plan.model_triangles;
  const StoreSummary& facts = store.summary();
  if (!options.quiet && summary.cells_baked > 0 && summary.cells_without_far_field == summary.cells_baked &&
      model_triangles > config.near_budget && facts.chunks > 0) {
    const std::uint64_t per_chunk = (model_triangles + facts.chunks - 1) / facts.chunks;
    const std::vector<SourceFileRecord> sources = store.sources();
    const std::string model = sources.size() == 1 ? sources[0].path : std::string("MODEL");
    const std::uint64_t suggested = std::max<std::uint64_t>(64, std::min(per_chunk / 8, config.near_budget / 16));
    std::fprintf(stderr,
                 "note: no baked cell has a far field although the model (%llu triangles) exceeds the near budget "
                 "(%llu): its %llu chunk(s) of ~%llu triangles each reach into every cull box; ingest it again "
                 "with smaller chunks, e.g. `cellbake ingest %s --store %s --chunk-triangles %llu`\n",
                 (unsigned long long)model_triangles, (unsigned long long)config.near_budget,
                 (unsigned long long)facts.chunks, (unsigned long long)per_chunk, model.c_str(), config.store.c_str(),
                 (unsigned long long)suggested);
  }
}

}  // namespace

BakeSummary run_bake(const BakeConfig& given, const BakeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  validate_bake_config(given);
  const int threads = drawing_worker_threads(options.threads);
  require_sound_store(given.store, options.check_store);  // a damaged store bakes nothing
  GeometryStore store(given.store);
  const BakePlan plan = plan_bake(given, options, store);
  const BakeConfig& config = plan.config;
  print_plan_notes(plan, options);

  std::filesystem::create_directories(std::filesystem::absolute(config.database).parent_path());
  CellDb db(config.database, CellDb::Mode::read_write);
  const CellDbLock lock(config.database, "baked");  // one bake per database; a second one stops here
  const std::string store_hash = store.summary().content_hash;
  record_bake_meta(db, plan, store_hash);

  BakeSummary summary;
  summary.cells_selected = plan.cells.size();
  const std::vector<std::unique_ptr<CellWork>> queued =
      queue_cells(plan.cells, config, store_hash, db, options.force, summary);
  ChunkWidths widths;  // outlives the cells' graph
  for (const auto& w : queued) w->widths = &widths;
  ProgressBar progress("bake", queued.size(), "cells");
  bake_queued_cells(queued, threads, config, options, store, db, progress, summary);
  if (!options.quiet) progress.finish();
  note_chunks_too_coarse(summary, plan, store, options);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace cellbake
