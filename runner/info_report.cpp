#include "runner/info_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "pipeline/bake_config.h"
#include "pipeline/bake_estimate.h"
#include "pipeline/cell_grid.h"
#include "pipeline/floor_regions.h"
#include "runner/number_text.h"
#include "runner/store_status.h"
#include "stages/model_analysis/floor_finder.h"
#include "stages/model_analysis/storey_units.h"
#include "stages/model_analysis/up_axis_from_geometry.h"

namespace cellbake {
namespace {

constexpr double kEyeHeight = kEyeHeightMetres;  // above the floor, metres (pipeline/floor_regions.h)
constexpr int kTargetCellsPerFloor = 64;
constexpr std::uint64_t kMinChunks = 16;  // fewer: re-ingest with smaller chunks for a far field
constexpr std::uint64_t kManyCells = 4096;  // more in a suggested bake: say that units may not be metres

struct UpUsed {
  std::string axis;  // "z" or "y"
  std::string why;
};

// The given axis, else the recorded one, else a sure answer from the geometry, else z.
UpUsed up_to_use(const GeometryStore& store, const InfoModelFile* model, const std::string& given) {
  const StoreSummary& summary = store.summary();
  if (!given.empty())
    return {given,
            summary.up.empty() || summary.up == given ? "--up" : "--up; the store records " + summary.up};
  if (!summary.up.empty())
    return {summary.up, summary.up_source.empty() ? "recorded at ingest" : summary.up_source};
  // A model file's ingest has already asked the geometry (unsure, or it would have recorded the answer).
  if (model) return {"z", "assumed: " + model->ingest.up_source};
  const UpAxisGuess guess = up_axis_from_geometry(store);
  if (!guess.axis.empty()) return {guess.axis, "not recorded; detected from the geometry: " + guess.evidence};
  return {"z", "not recorded; assumed: the geometry is not conclusive: " + guess.evidence};
}

struct Suggestion {
  bool found = false;
  double unit = 1;       // metres per model unit the suggestion takes (storey_units.h; 1: metres)
  std::string unit_name = "metres";
  std::size_t floor = 0;  // index into the floors
  double eye = 0;
  bool object = false;  // lower than eye height above its floor: cells around it at its mid-height
  Box3d region;
  double cell_size = 0;
  std::uint64_t cells = 0;
  std::uint64_t near_budget = 0;
  BakeEstimate estimate;
  int threads = 1;
  std::string command;
};

// 2-4 units for a building-sized floor (about kTargetCellsPerFloor cells),
// a quarter of the floor's longer side for a small model; rounded to 0.5
// (or two significant digits under 2).
double suggest_cell_size(double side_a, double side_b) {
  const double longer = std::max(side_a, side_b);
  if (longer < 8) {
    const double c = std::max(longer, 1e-3) / 4;
    const double scale = std::pow(10.0, std::floor(std::log10(c)) - 1);
    return std::round(c / scale) * scale;
  }
  const double c = std::clamp(std::sqrt(side_a * side_b / kTargetCellsPerFloor), 2.0, 4.0);
  return std::round(c * 2) / 2;
}

// `v` to hundredths, or to `step` (runner/number_text.h).
std::string number(double v, double step = 0.01) { return decimal_text(v, step); }

// The rounding step for a region's corners: hundredths, or finer for cells
// under a metre (three significant digits of the cell size).
double region_step(double cell_size) {
  return std::min(0.01, std::pow(10.0, std::floor(std::log10(cell_size)) - 2));
}

std::string shell_word(const std::string& path) {
  return path.find_first_of(" '\"$\\") == std::string::npos ? path : "'" + path + "'";
}

// `store_name`: the store the bake line reads (the store itself or the one the
// ingest line writes). Lengths in metres (eye height, cell sizes) are divided by
// `unit`, the metres one model unit is taken to be.
Suggestion suggest_bake(const std::string& store_name, const GeometryStore& store, const std::string& up,
                        const FloorFinderResult& found, const ModelUnit& unit) {
  Suggestion s;
  s.unit = unit.metres;
  s.unit_name = unit.name;
  if (found.floors.empty()) return s;
  // The main floor: the one most rays reach with something above it (indoors), else the widest.
  std::size_t best = 0;
  for (std::size_t f = 1; f < found.floors.size(); ++f) {
    const Floor &a = found.floors[f], &b = found.floors[best];
    if (a.covered_rays > b.covered_rays || (a.covered_rays == b.covered_rays && a.rays > b.rays)) best = f;
  }
  const int u = up == "y" ? 1 : 2, ha = 0, hb = up == "y" ? 2 : 1;
  const Floor& floor = found.floors[best];
  s.found = true;
  s.floor = best;
  s.region = walkable_extent(floor);
  s.cell_size = suggest_cell_size(unit.metres * (s.region.hi[ha] - s.region.lo[ha]),
                                  unit.metres * (s.region.hi[hb] - s.region.lo[hb]));
  if (unit.metres != 1) {  // back to model units, two significant digits (350 cm, 140 inches)
    const double c = s.cell_size / unit.metres, scale = std::pow(10.0, std::floor(std::log10(c)) - 1);
    s.cell_size = std::round(c / scale) * scale;
  }
  s.eye = floor.height + kEyeHeight / unit.metres;
  // A model lower than eye height above its main floor (an object, whose
  // "floor" is its top; the bake refuses eyes that far above it): cells
  // around it at its mid-height, over its footprint grown by one cell, so
  // that level views from them see it.
  const Box3d& bounds = store.summary().bounds;
  s.object = s.eye > bounds.hi[u] + s.cell_size;
  if (s.object) {
    s.eye = 0.5 * (bounds.lo[u] + bounds.hi[u]);
    s.region = bounds;
    for (int a : {ha, hb}) {
      s.region.lo[a] -= s.cell_size;
      s.region.hi[a] += s.cell_size;
    }
  }
  s.region.lo[u] = s.region.hi[u] = s.eye;
  s.cells = enumerate_cells({s.region}, s.cell_size).size();
  const std::uint64_t triangles = store.summary().triangles;
  s.near_budget = effective_near_budget(BakeConfig{}, triangles);
  if (s.near_budget > triangles / 2)
    s.near_budget = std::max<std::uint64_t>(1, triangles / 4);  // leave a far field (a small model)
  s.threads = int(std::max(1u, std::thread::hardware_concurrency()));
  s.estimate = estimate_bake(s.cells, BakeConfig{}.face_size, s.threads, triangles);
  std::string out = std::filesystem::path(store_name).filename().string();
  for (const char* suffix : {".store.db", ".db"})
    if (out.size() > std::string(suffix).size() && out.ends_with(suffix)) {
      out.resize(out.size() - std::string(suffix).size());
      break;
    }
  const Box3d& r = s.region;
  const double step = region_step(s.cell_size);
  s.command = "cellbake bake --store " + shell_word(store_name) + " --up " + up + " --region " +
              number(r.lo.x, step) + "," + number(r.lo.y, step) + "," + number(r.lo.z, step) + "," +
              number(r.hi.x, step) + "," + number(r.hi.y, step) + "," + number(r.hi.z, step) +
              " --cell-size " + number(s.cell_size, step) + " --near-budget " +
              std::to_string(s.near_budget) + " --out " + shell_word(out + ".cells.db");
  return s;
}

// "cellbake ingest MODEL --store NAME.store.db", with --up when the store was
// given one or records none (so the kept store holds the axis info used), and
// the --chunk-triangles the temporary store was read with.
std::string ingest_command(const InfoModelFile& model, const GeometryStore& store, const UpUsed& up,
                           const std::string& given) {
  std::string line =
      "cellbake ingest " + shell_word(model.model) + " --store " + shell_word(model.store_name);
  if (!given.empty() || store.summary().up.empty()) line += " --up " + up.axis;
  if (model.chunk_triangles > 0) line += " --chunk-triangles " + std::to_string(model.chunk_triangles);
  return line;
}

std::vector<std::string> ingest_warnings(const IngestReport& r) {
  std::vector<std::string> w = r.texture_warnings;
  w.insert(w.end(), r.input_warnings.begin(), r.input_warnings.end());
  if (!r.up_warning.empty()) w.push_back(r.up_warning);
  return w;
}

void print_json(const GeometryStore& store, const InfoModelFile* model, const std::string& ingest,
                const UpUsed& up, const FloorFinderResult& found, const Suggestion& s, const StoreyUnits& units) {
  nlohmann::json j = store_status_json(store);
  if (model) {
    j["kind"] = "model_file";
    j["path"] = model->model;
    j["store"] = model->store_name;
    j["ingest"] = ingest;
    j["ingest_seconds"] = model->seconds;
    j["warnings"] = ingest_warnings(model->ingest);
  }
  j["up_used"] = up.axis;
  j["up_used_source"] = up.why;
  if (!model)
    if (const std::size_t c = suggested_chunk_triangles(store.summary())) j["chunk_triangles_hint"] = c;
  j["floor_search"] = {
      {"rays", found.rays}, {"rays_hit", found.rays_hit}, {"ray_spacing", found.ray_spacing}};
  nlohmann::json floors = nlohmann::json::array();
  for (const Floor& f : found.floors)
    floors.push_back({{"height", f.height},
                      {"rays", f.rays},
                      {"covered_rays", f.covered_rays},
                      {"extent",
                       {{"min", {f.extent.lo.x, f.extent.lo.y, f.extent.lo.z}},
                        {"max", {f.extent.hi.x, f.extent.hi.y, f.extent.hi.z}}}}});
  j["floors"] = floors;
  nlohmann::json fitting = nlohmann::json::array();
  for (const ModelUnit& u : units.fitting) fitting.push_back(u.name);
  j["units"] = {{"storey", units.storey},
                {"metres_plausible", units.metres_plausible},
                {"fitting", fitting},
                {"taken_as", s.unit_name},
                {"metres_per_unit", s.unit},
                {"evidence", units.evidence}};
  if (s.found) {
    const Box3d& r = s.region;
    j["suggested"] = {{"floor", found.floors[s.floor].height},
                      {"eye_height", s.eye},
                      {"region", {r.lo.x, r.lo.y, r.lo.z, r.hi.x, r.hi.y, r.hi.z}},
                      {"cell_size", s.cell_size},
                      {"cells", s.cells},
                      {"near_budget", s.near_budget},
                      {"threads", s.threads},
                      {"estimated_seconds", s.estimate.seconds},
                      {"estimated_bytes", s.estimate.bytes},
                      {"command", s.command}};
  } else {
    j["suggested"] = nullptr;
  }
  std::printf("%s\n", j.dump(2).c_str());
}

}  // namespace

std::size_t suggested_chunk_triangles(const StoreSummary& summary) {
  if (summary.chunks >= kMinChunks || summary.triangles < 2 * kMinChunks) return 0;
  std::size_t c = 16;
  while (2 * c * kMinChunks <= summary.triangles && 2 * c < 4096) c *= 2;
  return c;
}

void print_info(const GeometryStore& store, const InfoModelFile* model, const std::string& given, bool json) {
  const UpUsed up = up_to_use(store, model, given);
  // Storeys implausible in metres but plausible in other units: the floors
  // found again with the finder's lengths (headroom, separation, bins) in those.
  const ModelFloors floors = find_model_floors(store, up.axis == "y" ? 1 : 2);
  const FloorFinderResult& found = floors.found;
  const StoreyUnits& units = floors.units;
  const ModelUnit& unit = floors.unit;
  const std::string store_name = model ? model->store_name : store.path().string();
  const Suggestion s = suggest_bake(store_name, store, up.axis, found, unit);
  const std::string ingest = model ? ingest_command(*model, store, up, given) : "";
  if (json) return print_json(store, model, ingest, up, found, s, units);

  const StoreSummary& summary = store.summary();
  if (model)
    std::printf("%s: a model file, read into a temporary geometry store in %.1f s (removed again):\n",
                model->model.c_str(), model->seconds);
  if (model)
    print_store_facts(store, stdout);
  else
    print_store_status(store, stdout);
  if (summary.up != up.axis) std::printf("up axis used: %s (%s)\n", up.axis.c_str(), up.why.c_str());
  if (model)
    for (const std::string& w : ingest_warnings(model->ingest))
      std::printf("%s%s\n", w.rfind("warning:", 0) == 0 ? "" : "warning: ", w.c_str());
  std::printf("floors (rays cast down on a grid %.3g apart; %llu of %llu rays hit the model; up %s):\n",
              found.ray_spacing, (unsigned long long)found.rays_hit, (unsigned long long)found.rays,
              up.axis.c_str());
  if (found.floors.empty()) std::printf("  none found (no wide upward-facing surface with headroom)\n");
  for (std::size_t f = 0; f < found.floors.size(); ++f) {
    const Floor& fl = found.floors[f];
    std::printf("  %s = %s: %llu rays (%.0f %% of them covered above)%s\n", up.axis.c_str(),
                number(fl.height, s.found ? region_step(s.cell_size) : 0.01).c_str(),
                (unsigned long long)fl.rays,
                fl.rays ? 100.0 * double(fl.covered_rays) / double(fl.rays) : 0.0,
                s.found && f == s.floor ? "  <- main floor" : "");
  }
  if (!s.found) {
    if (model) std::printf("no suggested bake; ingest it:\n  %s\n", ingest.c_str());
    std::printf("then choose a region with `cellbake render %s --out look.png` (a look at the model)\n",
                shell_word(store_name).c_str());
    return;
  }
  const Box3d& r = s.region;
  const double step = region_step(s.cell_size);
  if (!units.fitting.empty()) std::printf("units: %s\n", units.evidence.c_str());
  if (s.unit != 1)
    std::printf("suggested bake (model units taken as %s: 1 unit = %g m; floors found again with lengths in them):\n",
                s.unit_name.c_str(), s.unit);
  else
    std::printf("suggested bake (model units taken as metres):\n");
  if (s.object)
    std::printf(
        "  eye height: %s = %s (the model's mid-height: it is lower than %g above its floor %s, an "
        "object rather than a place to walk through)\n",
        up.axis.c_str(), number(s.eye, step).c_str(), kEyeHeight / s.unit,
        number(found.floors[s.floor].height, step).c_str());
  else
    std::printf("  eye height: %s = %s (floor %s + %g)\n", up.axis.c_str(), number(s.eye, step).c_str(),
                number(found.floors[s.floor].height, step).c_str(), kEyeHeight / s.unit);
  std::printf("  region: (%s, %s, %s) .. (%s, %s, %s), %s\n", number(r.lo.x, step).c_str(),
              number(r.lo.y, step).c_str(), number(r.lo.z, step).c_str(), number(r.hi.x, step).c_str(),
              number(r.hi.y, step).c_str(), number(r.hi.z, step).c_str(),
              s.object ? "the model's footprint grown by one cell (cells around it)"
                       : "the floor's extent (under a roof if any)");
  std::printf("  cell size: %s -> %llu cells\n", number(s.cell_size, step).c_str(),
              (unsigned long long)s.cells);
  if (s.cells > kManyCells)
    std::printf(
        "  note: %llu cells is a large bake: cells are sized for a model in metres; if its units are "
        "smaller (centimetres, millimetres), give a larger --cell-size, or bake part of it with --cells\n",
        (unsigned long long)s.cells);
  std::printf("  near budget: %llu triangles per cell (of %llu: the rest is far field)\n",
              (unsigned long long)s.near_budget, (unsigned long long)summary.triangles);
  if (model && model->chunk_triangles > 0)
    std::printf(
        "  chunks of at most %zu triangles: %llu chunks, so the far field (whole chunks outside a cell's "
        "cull box) is not empty\n",
        model->chunk_triangles, (unsigned long long)summary.chunks);
  else if (const std::size_t c = model ? 0 : suggested_chunk_triangles(summary))
    std::printf(
        "  note: only %llu chunks; the far field is whole chunks outside a cell's cull box: ingest again "
        "with --chunk-triangles %zu for one\n",
        (unsigned long long)summary.chunks, c);
  std::printf(
      "  estimated bake: ~%s on %d threads (%.1f core-seconds per cell: the demo plant's %.1f at 512^2 faces "
      "scaled to this model's size; within about 2x), ~%.1f MB\n",
      duration_text(s.estimate.seconds).c_str(), s.threads, s.estimate.core_seconds_per_cell,
      kMeasuredCoreSecondsPerCell, s.estimate.bytes / 1e6);
  if (model) std::printf("  %s\n", ingest.c_str());
  std::printf("  %s\n", s.command.c_str());
  std::printf("  (`bake ... --dry-run` checks it; `--cells 1-4` bakes a few cells first)\n");
}

}  // namespace cellbake
