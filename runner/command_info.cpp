// `cellbake info PATH [--json]`: what a file is and, for a geometry store, a
// suggested bake — the store's facts (as `status` prints them), the floors
// found by casting rays down over a grid (stages/floor_finder.h), and a
// `cellbake bake` command line: a region at eye height over the main floor, a
// cell size, the near budget the bake would use and an estimated time.
// Model units are taken as metres (eye height 1.7, cells of 2-4).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "pipeline/bake_config.h"
#include "pipeline/bake_estimate.h"
#include "pipeline/cell_grid.h"
#include "runner/commands.h"
#include "runner/store_status.h"
#include "stages/floor_finder.h"
#include "storage/database_kind.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

constexpr double kEyeHeight = 1.7;  // above the floor, model units taken as metres
constexpr int kTargetCellsPerFloor = 64;

struct Suggestion {
  bool found = false;
  std::size_t floor = 0;  // index into the floors
  double eye = 0;
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

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", std::round(v * 100) / 100 + 0.0);  // + 0.0: no "-0"
  return buf;
}

std::string shell_word(const std::string& path) {
  return path.find_first_of(" '\"$\\") == std::string::npos ? path : "'" + path + "'";
}

Suggestion suggest_bake(const std::string& path, const GeometryStore& store, const std::string& up,
                        const FloorFinderResult& found) {
  Suggestion s;
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
  s.eye = floor.height + kEyeHeight;
  s.region = floor.covered_extent.empty() ? floor.extent : floor.covered_extent;  // indoors, else all of it
  s.region.lo[u] = s.region.hi[u] = s.eye;
  s.cell_size = suggest_cell_size(s.region.hi[ha] - s.region.lo[ha], s.region.hi[hb] - s.region.lo[hb]);
  s.cells = enumerate_cells({s.region}, s.cell_size).size();
  const std::uint64_t triangles = store.summary().triangles;
  s.near_budget = effective_near_budget(BakeConfig{}, triangles);
  if (s.near_budget >= triangles)
    s.near_budget = std::max<std::uint64_t>(1, triangles / 4);  // leave a far field
  s.threads = int(std::max(1u, std::thread::hardware_concurrency()));
  s.estimate = estimate_bake(s.cells, BakeConfig{}.face_size, s.threads);
  std::string out = std::filesystem::path(path).filename().string();
  for (const char* suffix : {".store.db", ".db"})
    if (out.size() > std::string(suffix).size() && out.ends_with(suffix)) {
      out.resize(out.size() - std::string(suffix).size());
      break;
    }
  const Box3d& r = s.region;
  s.command = "cellbake bake --store " + shell_word(path) + " --up " + up + " --region " + number(r.lo.x) +
              "," + number(r.lo.y) + "," + number(r.lo.z) + "," + number(r.hi.x) + "," + number(r.hi.y) +
              "," + number(r.hi.z) + " --cell-size " + number(s.cell_size) + " --near-budget " +
              std::to_string(s.near_budget) + " --out " + shell_word(out + ".cells.db");
  return s;
}

void info_store(const std::string& path, bool json) {
  const GeometryStore store(path);
  const StoreSummary& summary = store.summary();
  const std::string up = summary.up.empty() ? "z" : summary.up;
  FloorFinderParams params;
  params.up_axis = up == "y" ? 1 : 2;
  const FloorFinderResult found = find_floors(store, params);
  const Suggestion s = suggest_bake(path, store, up, found);
  if (json) {
    nlohmann::json j = store_status_json(store);
    j["up_used"] = up;
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
    return;
  }
  print_store_status(store, stdout);
  std::printf("floors (rays cast down on a grid %.3g apart; %llu of %llu rays hit the model; up %s):\n",
              found.ray_spacing, (unsigned long long)found.rays_hit, (unsigned long long)found.rays,
              up.c_str());
  if (found.floors.empty()) std::printf("  none found (no wide upward-facing surface with headroom)\n");
  for (std::size_t f = 0; f < found.floors.size(); ++f) {
    const Floor& fl = found.floors[f];
    std::printf("  %s = %s: %llu rays (%.0f %% of them covered above)%s\n", up.c_str(),
                number(fl.height).c_str(), (unsigned long long)fl.rays,
                fl.rays ? 100.0 * double(fl.covered_rays) / double(fl.rays) : 0.0,
                s.found && f == s.floor ? "  <- main floor" : "");
  }
  if (!s.found) {
    std::printf("no suggested bake: choose a region with `cellbake render %s` (a look at the model)\n",
                path.c_str());
    return;
  }
  const Box3d& r = s.region;
  std::printf("suggested bake (model units taken as metres):\n");
  std::printf("  eye height: %s = %s (floor %s + %.1f)\n", up.c_str(), number(s.eye).c_str(),
              number(found.floors[s.floor].height).c_str(), kEyeHeight);
  std::printf("  region: (%s, %s, %s) .. (%s, %s, %s), the floor's extent (under a roof if any)\n",
              number(r.lo.x).c_str(), number(r.lo.y).c_str(), number(r.lo.z).c_str(), number(r.hi.x).c_str(),
              number(r.hi.y).c_str(), number(r.hi.z).c_str());
  std::printf("  cell size: %s -> %llu cells\n", number(s.cell_size).c_str(), (unsigned long long)s.cells);
  std::printf("  near budget: %llu triangles per cell (of %llu: the rest is far field)\n",
              (unsigned long long)s.near_budget, (unsigned long long)summary.triangles);
  std::printf(
      "  estimated bake: ~%s on %d threads (%.1f core-seconds per cell measured on the demo plant at 512^2 "
      "faces), ~%.1f MB\n",
      duration_text(s.estimate.seconds).c_str(), s.threads, s.estimate.core_seconds_per_cell,
      s.estimate.bytes / 1e6);
  std::printf("  %s\n", s.command.c_str());
  std::printf("  (`bake ... --dry-run` checks it; `--cells 1-4` bakes a few cells first)\n");
}

bool is_sqlite_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char header[16] = {};
  in.read(header, sizeof header);
  return in.gcount() == 16 && std::string(header, 15) == "SQLite format 3";
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Look at a model before baking: a geometry store's facts, its floors and a suggested bake command");
  cmd->add_option("path", *path, "Geometry store (ingest's output), model file or cell database")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", *json, "Print the same as one JSON object");
  cmd->footer(
      "Example:\n  cellbake info house.store.db          # floors, a suggested region, cell size and budget\n"
      "  cellbake info house.store.db --json");
  cmd->callback([path, json] {
    if (database_kind(*path) == DatabaseKind::geometry_store) return info_store(*path, *json);
    if (is_sqlite_file(*path)) {
      if (*json)
        std::printf("%s\n", nlohmann::json{{"kind", "cell_database"},
                                           {"path", *path},
                                           {"see", "cellbake status --json " + shell_word(*path)}}
                                .dump(2)
                                .c_str());
      else
        std::printf("%s: a cell database (or another SQLite file): `cellbake status %s` describes it\n",
                    path->c_str(), shell_word(*path).c_str());
      return;
    }
    const std::filesystem::path p(*path);
    std::string stem = p.filename().string();
    if (const auto dot = stem.find('.'); dot != std::string::npos && dot > 0) stem.resize(dot);
    const std::string store = stem + ".store.db";
    const std::string ingest = "cellbake ingest " + shell_word(*path) + " --store " + shell_word(store);
    if (*json) {
      std::printf("%s\n", nlohmann::json{{"kind", "model_file"},
                                         {"path", *path},
                                         {"ingest", ingest},
                                         {"then", "cellbake info " + shell_word(store)}}
                              .dump(2)
                              .c_str());
      return;
    }
    std::printf(
        "%s: a model file (not a geometry store); ingest it first, then ask again:\n  %s   # add --up y "
        "for a Y-up OBJ/PLY (glTF is Y-up by specification)\n  cellbake info %s\n",
        path->c_str(), ingest.c_str(), shell_word(store).c_str());
  });
}

}  // namespace cellbake
