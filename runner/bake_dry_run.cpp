#include "runner/bake_dry_run.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include <nlohmann/json.hpp>

#include "pipeline/bake_estimate.h"
#include "pipeline/bake_projection.h"
#include "pipeline/stratified_cells.h"
#include "runner/console.h"
#include "runner/measured_estimate.h"
#include "runner/parallel.h"
#include "storage/geometry_store.h"
#include "storage/store_check.h"

namespace cellbake {
namespace {

// The key of a "section.key=value" override, trimmed.
std::string override_key(const std::string& assignment) {
  std::string key = assignment.substr(0, assignment.find('='));
  key.erase(0, key.find_first_not_of(" \t"));
  key.erase(key.find_last_not_of(" \t") + 1);
  return key;
}

std::string region_text(const Box3d& r) {
  return exact_number_text(r.lo.x) + "," + exact_number_text(r.lo.y) + "," + exact_number_text(r.lo.z) + "," +
         exact_number_text(r.hi.x) + "," + exact_number_text(r.hi.y) + "," + exact_number_text(r.hi.z);
}

std::string bytes_text(double b) {
  char buf[64];
  if (b < 1e4)
    std::snprintf(buf, sizeof buf, "%.1f KB", b / 1e3);
  else if (b < 1e6)
    std::snprintf(buf, sizeof buf, "%.0f KB", b / 1e3);
  else if (b < 1e9)
    std::snprintf(buf, sizeof buf, "%.1f MB", b / 1e6);
  else
    std::snprintf(buf, sizeof buf, "%.1f GB", b / 1e9);
  return buf;
}

// The selected floors: one entry per floor region, with the cell ids it holds.
struct FloorLine {
  FloorRegion floor;
  std::uint64_t cells = 0;
  std::int64_t first_id = 0, last_id = 0;
};

std::vector<FloorLine> floor_lines(const BakePlan& plan) {
  std::vector<FloorLine> lines;
  std::int64_t next = 1;
  for (const FloorRegion& r : plan.floors.regions) {
    FloorLine l;
    l.floor = r;
    l.cells = count_cells({r.region}, plan.config.cell_size);
    l.first_id = next;
    l.last_id = next + std::int64_t(l.cells) - 1;
    next += std::int64_t(l.cells);
    lines.push_back(l);
  }
  return lines;
}

nlohmann::json floors_json(const BakePlan& plan) {
  nlohmann::json selected = nlohmann::json::array();
  for (const FloorLine& l : floor_lines(plan)) {
    const Box3d& b = l.floor.region;
    selected.push_back({{"floor", l.floor.floor},
                        {"height", l.floor.height},
                        {"eye", l.floor.eye},
                        {"region", {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z}},
                        {"cells", l.cells},
                        {"first_id", l.first_id},
                        {"last_id", l.last_id}});
  }
  return {{"found", plan.floors.heights},
          {"eye_height", plan.floors.eye_height},
          {"units", plan.floors.unit.name},
          {"selected", selected},
          {"notes", plan.floors.notes}};
}

void print_floors(const BakePlan& plan) {
  const char* axis = plan.config.up == "y" ? "y" : "z";
  std::printf("floors: %zu found (as `cellbake info` finds them:", plan.floors.heights.size());
  for (std::size_t f = 0; f < plan.floors.heights.size(); ++f)
    std::printf("%s %zu at %s = %.3g", f ? "," : "", f, axis,
                std::abs(plan.floors.heights[f]) < 5e-4 ? 0.0 : plan.floors.heights[f]);
  std::printf("); eyes %g above each", plan.floors.eye_height);
  if (plan.floors.unit.metres != 1)
    std::printf(" (model units taken as %s, as `cellbake info` does)", plan.floors.unit.name.c_str());
  std::printf("\n");
  for (const FloorLine& l : floor_lines(plan))
    std::printf("  floor %d: --region %s: %llu cells, ids %lld..%lld\n", l.floor.floor,
                region_text(l.floor.region).c_str(), (unsigned long long)l.cells, (long long)l.first_id,
                (long long)l.last_id);
  for (const std::string& note : plan.floors.notes) std::printf("  note: %s\n", note.c_str());
}

nlohmann::json measured_json(const CellMeasurement& m) {
  return {{"cell_ids", m.ids},
          {"cells", m.cells_done},
          {"threads", m.threads},
          {"cpu_seconds", m.cpu_seconds},
          {"wall_seconds", m.wall_seconds},
          {"cpu_seconds_per_cell", m.cpu_seconds / double(m.cells_done)},
          {"in_thread_seconds_per_cell", m.in_thread_seconds / double(m.cells_done)},
          {"bytes_per_cell", m.bytes / double(m.cells_done)},
          {"peak_rss_bytes", m.peak_rss_bytes}};
}

nlohmann::json projection_json(const BakeProjection& p) {
  nlohmann::json shards = nlohmann::json::array();
  for (const ShardProjection& s : p.shards)
    shards.push_back({{"shards", s.shards},
                      {"threads_per_shard", s.threads_per_shard},
                      {"cells_per_shard", s.cells_per_shard},
                      {"wall_seconds", s.wall_seconds}});
  return {{"cells", p.cells},
          {"cpu_seconds_per_cell", p.cpu_seconds_per_cell},
          {"bytes_per_cell", p.bytes_per_cell},
          {"cpu_seconds", p.cpu_seconds},
          {"bytes", p.bytes},
          {"threads", p.threads},
          {"wall_seconds", p.wall_seconds},
          {"slurm", shards}};
}

const char* plural(std::uint64_t n) { return n == 1 ? "" : "s"; }

void print_measurement(const CellMeasurement& m, const BakeProjection& p, std::size_t regions) {
  std::printf("measured: %llu cell%s (ids %s; stratified over %zu region%s and their grids) in %.1f s on %d "
              "thread%s: %.1f CPU-s per cell (the bake process's user + system time, its setup included; in its "
              "stages %.1f s), %s per cell, peak memory %s\n",
              (unsigned long long)m.cells_done, plural(m.cells_done), cell_selection_text(m.ids).c_str(), regions,
              plural(regions), m.wall_seconds, m.threads, plural(std::uint64_t(m.threads)), p.cpu_seconds_per_cell,
              m.in_thread_seconds / double(m.cells_done), bytes_text(p.bytes_per_cell).c_str(),
              bytes_text(double(m.peak_rss_bytes)).c_str());
  std::printf("projection for %llu cell%s: %.1f CPU-hours, %s; %s on one machine with %d thread%s",
              (unsigned long long)p.cells, plural(p.cells), p.cpu_seconds / 3600, bytes_text(p.bytes).c_str(),
              duration_text(p.wall_seconds).c_str(), p.threads, plural(std::uint64_t(p.threads)));
  for (std::size_t i = 0; i < p.shards.size(); ++i) {
    const ShardProjection& s = p.shards[i];
    if (i == 0)
      std::printf("; on Slurm, %d shard%s of %d thread%s each: %s", s.shards, plural(std::uint64_t(s.shards)),
                  s.threads_per_shard, plural(std::uint64_t(s.threads_per_shard)),
                  duration_text(s.wall_seconds).c_str());
    else
      std::printf(", %d shards: %s", s.shards, duration_text(s.wall_seconds).c_str());
    std::printf(" (%llu cell%s a shard)", (unsigned long long)s.cells_per_shard, plural(s.cells_per_shard));
  }
  std::printf("; every thread on a core of its own\n");
}

}  // namespace

std::string exact_number_text(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::vector<std::string> bake_arguments_for_plan(const BakeCommandOptions& o, const BakePlan& plan) {
  std::vector<std::string> args;
  if (!o.config_file.empty()) args.push_back(o.config_file);
  if (!o.store.empty()) args.insert(args.end(), {"--store", o.store});
  args.insert(args.end(), {"--up", plan.config.up, "--floors", "none"});
  for (const Box3d& r : plan.config.regions) args.insert(args.end(), {"--region", region_text(r)});
  if (o.cell_size > 0) args.insert(args.end(), {"--cell-size", exact_number_text(o.cell_size)});
  if (o.near_budget >= 0) args.insert(args.end(), {"--near-budget", std::to_string(o.near_budget)});
  if (o.face_size > 0) args.insert(args.end(), {"--face-size", std::to_string(o.face_size)});
  for (const std::string& s : o.sets) {
    const std::string key = override_key(s);
    if (key != "output.database" && key != "cells.floors") args.insert(args.end(), {"--set", s});
  }
  return args;
}

void run_bake_dry_run(const BakeConfig& given, const BakeCommandOptions& options, const DryRunRequest& request) {
  validate_bake_config(given);
  require_sound_store(given.store, options.run.check_store);
  const GeometryStore store(given.store);
  const BakePlan plan = plan_bake(given, options.run, store);
  const BakeConfig& c = plan.config;
  const int threads = worker_threads(options.run.threads);
  const BakeEstimate e = estimate_bake(plan.cells.size(), c.face_size, threads, plan.model_triangles);
  const bool no_far_field = plan.model_triangles <= c.near_budget;

  CellMeasurement measured;
  BakeProjection projection;
  if (request.measure > 0 && !plan.cells.empty()) {
    const std::vector<CellSpec> chosen = stratified_cells(plan.cells, std::size_t(request.measure));
    std::vector<std::int64_t> ids;
    for (const CellSpec& cell : chosen) ids.push_back(cell.id);
    if (!quiet_output())
      std::fprintf(stderr, "measuring %zu of the %zu selected cells (%s) on %d threads in a temporary database...\n",
                   ids.size(), plan.cells.size(), cell_selection_text(ids).c_str(), threads);
    measured = measure_cells(bake_arguments_for_plan(options, plan), ids, threads, quiet_output());
    if (measured.interrupted) {
      std::fprintf(stderr, "\ninterrupted — the measurement's temporary database was removed; nothing written\n");
      std::exit(130);
    }
    projection = project_bake({measured.cells_done, measured.cpu_seconds, measured.bytes}, plan.cells.size(),
                              threads, request.shards, threads);
  }

  if (request.json) {
    nlohmann::json j{{"dry_run", true},
                     {"database", c.database.string()},
                     {"database_exists", std::filesystem::exists(c.database)},
                     {"store", c.store.string()},
                     {"model_triangles", plan.model_triangles},
                     {"up", c.up},
                     {"cell_size", c.cell_size},
                     {"cells_total", plan.cells_total},
                     {"cells_selected", plan.cells.size()},
                     {"near_budget", c.near_budget},
                     {"face_size", c.face_size},
                     {"threads", threads},
                     {"estimated_seconds", e.seconds},
                     {"estimated_core_seconds_per_cell", e.core_seconds_per_cell},
                     {"estimated_bytes_per_cell", e.bytes_per_cell},
                     {"estimated_bytes", e.bytes},
                     {"no_far_field", no_far_field}};
    nlohmann::json regions = nlohmann::json::array();
    for (const Box3d& r : c.regions) regions.push_back({r.lo.x, r.lo.y, r.lo.z, r.hi.x, r.hi.y, r.hi.z});
    j["regions"] = regions;
    nlohmann::json ids = nlohmann::json::array();
    for (const CellSpec& cell : plan.cells) ids.push_back(cell.id);
    j["cell_ids"] = ids;
    if (!plan.floors.regions.empty()) j["floors"] = floors_json(plan);
    if (measured.cells_done > 0) {
      j["measured"] = measured_json(measured);
      j["projection"] = projection_json(projection);
    }
    if (!plan.up_note.empty()) j["up_note"] = plan.up_note;
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  if (!plan.up_note.empty()) std::fprintf(stderr, "%s\n", plan.up_note.c_str());
  std::printf("dry run: nothing written (%s %s)\n", c.database.c_str(),
              std::filesystem::exists(c.database) ? "exists; a bake resumes it" : "would be created");
  std::printf("store: %s, %llu triangles, up %s\n", c.store.c_str(), (unsigned long long)plan.model_triangles,
              c.up.c_str());
  if (!plan.floors.regions.empty()) print_floors(plan);
  std::printf("cells: %zu selected of %llu (cell size %g)", plan.cells.size(), (unsigned long long)plan.cells_total,
              c.cell_size);
  if (!plan.cells.empty())
    std::printf(", ids %lld..%lld", (long long)plan.cells.front().id, (long long)plan.cells.back().id);
  std::printf("\nnear budget: %llu triangles per cell%s\n", (unsigned long long)c.near_budget,
              no_far_field ? " (the whole model fits: no far field; lower it with --near-budget)" : "");
  std::printf(
      "estimate: ~%s on %d threads (%.1f core-seconds per cell at %d² faces), ~%.0f KB per cell, ~%.1f MB "
      "in all (the demo plant's figures scaled to this model's size; a guide, not a promise%s)\n",
      duration_text(e.seconds).c_str(), threads, e.core_seconds_per_cell, c.face_size, e.bytes_per_cell / 1e3,
      e.bytes / 1e6, request.measure > 0 ? "; measured below" : ": --measure K bakes K cells to measure");
  if (measured.cells_done > 0) print_measurement(measured, projection, c.regions.size());
}

}  // namespace cellbake
