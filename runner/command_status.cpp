// `cellbake status DB... [--json] [--check | --repair]`: what is done, failed
// (with each failed cell's error) and pending of the configuration's cells, the
// bake's parameters (the main ones; every one with -v or --json), totals, time
// per stage and a content hash over every finished cell. --check recomputes each cell's
// content hash from its rows and decodes every blob, validates the meta values
// and checks each cell against its grid place and the store it was baked from
// (pipeline/cell_database_check.h); --repair marks the
// damaged cells pending so the next bake redoes them. A geometry store given
// instead prints what it holds (runner/store_status.h).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "runner/commands.h"
#include "runner/console.h"
#include "runner/store_status.h"
#include "stages/hashing.h"
#include "pipeline/cell_database_check.h"
#include "storage/cell_check.h"
#include "storage/cell_db.h"
#include "storage/cell_db_lock.h"
#include "storage/database_kind.h"
#include "storage/meta_values.h"
#include "storage/store_check.h"

namespace cellbake {
namespace {

// The cells of one configuration (databases with the same `config` meta: a
// bake and its shards or merge), counted once per id.
struct ConfigCells {
  std::uint64_t total = 0;                     // the configuration's cell count (cells_total meta)
  std::map<std::int64_t, std::string> state;  // id -> "done" | "failed" | "damaged"
};

struct Damaged {
  std::string database;
  std::int64_t id;
  std::string reason;
};

// One configuration's parameters: the database's meta `store` and the
// "key=value" lines of its meta `config` (describe_bake_config), regions apart.
struct BakeParameters {
  std::string store;
  std::vector<std::pair<std::string, std::string>> values;
  std::vector<std::string> regions;  // "x0,y0,z0,x1,y1,z1"
};

// "0.40000000000000002,1" -> "0.4,1": the config text keeps 17 digits (for hashing); people read the
// shortest form that reads back the same. Words that are not numbers stay as they are.
std::string tidy_numbers(const std::string& value) {
  std::string out, item;
  std::istringstream in(value);
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double d = std::strtod(item.c_str(), &end);
    if (!item.empty() && end == item.c_str() + item.size()) {
      char buf[64];
      // Whole numbers in full ("100000", not the shorter "1e+05").
      const auto r = std::abs(d) < 1e15 && d == std::floor(d)
                         ? std::to_chars(buf, buf + sizeof buf, static_cast<long long>(d))
                         : std::to_chars(buf, buf + sizeof buf, d);
      item.assign(buf, r.ptr);
    }
    out += (out.empty() ? "" : ",") + item;
  }
  return out;
}

BakeParameters parse_parameters(const std::string& store, const std::string& config_text) {
  BakeParameters p;
  p.store = store;
  std::istringstream in(config_text);
  for (std::string line; std::getline(in, line);) {
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos) continue;
    if (line.compare(0, eq, "region") == 0) p.regions.push_back(tidy_numbers(line.substr(eq + 1)));
    else p.values.emplace_back(line.substr(0, eq), tidy_numbers(line.substr(eq + 1)));
  }
  return p;
}

// "bake: store S, up z, cells.size 2, ..., 1 region: x0,y0,z0,x1,y1,z1": the
// parameters a reader checks first; with `all`, every one on its own line.
void print_parameters(const BakeParameters& p, bool all) {
  std::string line = "bake: store " + (p.store.empty() ? std::string("(unknown)") : p.store);
  if (all) {
    std::printf("%s\n", line.c_str());
    for (const auto& [k, v] : p.values) std::printf("  %s = %s\n", k.c_str(), v.c_str());
    for (const auto& r : p.regions) std::printf("  region = %s\n", r.c_str());
    return;
  }
  for (const char* key : {"up", "cells.size", "near.budget", "sample.face_size", "sample.backend", "samples.max",
                          "far.choice", "encode.image_format", "encode.quality", "encode.mesh_codec"})
    for (const auto& [k, v] : p.values)
      if (k == key) line += ", " + k + " " + v;
  line += ", " + std::to_string(p.regions.size()) + (p.regions.size() == 1 ? " region" : " regions");
  for (std::size_t i = 0; i < p.regions.size() && i < 3; ++i) line += (i ? "; " : ": ") + p.regions[i];
  if (p.regions.size() > 3) line += "; ...";
  std::printf("%s\n", line.c_str());
}

nlohmann::json parameters_json(const BakeParameters& p) {
  nlohmann::json values = nlohmann::json::object();
  for (const auto& [k, v] : p.values) values[k] = v;
  return {{"store", p.store}, {"parameters", values}, {"regions", p.regions}};
}

struct FailedCell {
  std::string database;
  std::int64_t id;
  std::string error;
};

// A cell seen in several databases keeps its best state: done over failed over damaged.
void note_state(std::string& have, const std::string& seen) {
  auto rank = [](const std::string& s) { return s == "done" ? 3 : s == "failed" ? 2 : s == "damaged" ? 1 : 0; };
  if (rank(seen) > rank(have)) have = seen;
}

// `status`'s command line.
struct StatusOptions {
  std::vector<std::string> dbs;
  bool json = false, check = false, repair = false;
};

// Geometry stores given: their summary (with --check, their problems), and
// nothing else (a cell database's counts make no sense for them). Throws when
// a store is damaged.
void show_store_status(const StatusOptions& opt) {
  if (opt.repair) throw std::invalid_argument("--repair mends cell databases; a damaged geometry store is re-ingested");
  nlohmann::json list = nlohmann::json::array();
  std::size_t damaged_stores = 0;
  for (const auto& path : opt.dbs) {
    const GeometryStore store(path);
    nlohmann::json j = store_status_json(store);
    if (!opt.json) print_store_status(store, stdout);
    if (opt.check) {
      const std::vector<StoreProblem> problems = check_store(path);
      nlohmann::json found = nlohmann::json::array();
      for (const auto& p : problems) {
        std::fprintf(stderr, "%s: %s\n", path.c_str(), describe(p).c_str());
        found.push_back({{"chunk", p.chunk_id}, {"reason", p.reason}});
      }
      j["problems"] = found;
      damaged_stores += !problems.empty();
      if (!opt.json)
        std::printf("check: %s\n", problems.empty() ? "sound (content hash, R-tree and every chunk blob agree)"
                                                      : (std::to_string(problems.size()) + " problem(s)").c_str());
    }
    list.push_back(std::move(j));
  }
  if (opt.json) std::printf("%s\n", (list.size() == 1 ? list[0] : list).dump(2).c_str());
  if (damaged_stores > 0)
    throw std::runtime_error(std::to_string(damaged_stores) +
                             " damaged geometry store(s) (problems listed above); re-ingest the model");
}

// A meta value --check found damaged.
struct DamagedMeta {
  std::string database, key, reason;
};

// What the cell databases hold together: sums of their totals, the cells of
// each configuration, what is damaged or failed, each configuration's
// parameters, and the done cells' content hashes.
struct StatusTotals {
  std::uint64_t bytes = 0, far = 0, samples = 0, delta_covered = 0, delta_removed = 0;
  std::uint64_t far_geometry = 0, geometry_tiles = 0, face_tiles = 0, replaced = 0, far_levels = 0, level_rows = 0;
  CellDbBytes by_kind;
  std::map<std::string, double> stage_seconds;
  std::map<std::string, ConfigCells> configs;
  std::vector<Damaged> damaged;
  std::vector<DamagedMeta> damaged_meta;
  std::vector<FailedCell> failed_cells;
  std::map<std::string, BakeParameters> parameters;  // by config text
  // Per-cell content hashes from every database, combined in id order, so a
  // merged database and its shards hash alike.
  std::map<std::int64_t, std::string> cell_hashes;
  nlohmann::json per_db = nlohmann::json::array();
};

// Adds one database's byte, triangle, sample and stage-time totals.
void add_database_totals(const CellDb& db, const CellDbTotals& t, StatusTotals& s) {
  s.bytes += t.bytes;
  s.far += t.far_triangles;
  s.far_geometry += t.far_geometry_triangles, s.geometry_tiles += t.geometry_tiles, s.face_tiles += t.face_tiles;
  s.replaced += t.replaced_triangles;
  s.far_levels += t.far_level_triangles, s.level_rows += t.far_level_rows;
  const CellDbBytes b = db.bytes_by_kind();
  s.by_kind.cells += b.cells, s.by_kind.colour += b.colour, s.by_kind.mesh += b.mesh, s.by_kind.near_list += b.near_list;
  s.by_kind.far_geometry += b.far_geometry;
  s.samples += t.samples;
  s.delta_covered += t.delta_covered_pixels;
  s.delta_removed += t.delta_removed_pixels;
  for (const auto& [k, v] : t.stage_seconds) s.stage_seconds[k] += v;
}

// --check: the meta values a reader uses (damaged ones kept and printed),
// then each cell against its grid place and the store it was baked from.
// Returns the damaged cells' reasons by id.
std::map<std::int64_t, std::string> check_database(const CellDb& db, const std::string& path, StatusTotals& s) {
  std::map<std::int64_t, std::string> reasons;
  for (const MetaProblem& p : check_database_meta(db)) {
    std::fprintf(stderr, "%s: meta '%s': %s\n", path.c_str(), p.key.c_str(), p.reason.c_str());
    s.damaged_meta.push_back({path, p.key, p.reason});
  }
  const CellCheckSetup setup = cell_check_setup(db);
  if (!setup.note.empty()) std::fprintf(stderr, "%s: note: %s\n", path.c_str(), setup.note.c_str());
  for (auto& p : check_cells(db, setup.context)) reasons[p.id] = std::move(p.reason);
  return reasons;
}

// Each stored cell's state in its configuration (damaged when it has a reason:
// from the check, or a row that could not be read), the done cells' content
// hashes, and the failed cells with their errors.
void note_cell_states(const CellDb& db, const std::string& path, std::map<std::int64_t, std::string>& reasons,
                      ConfigCells& cells, StatusTotals& s) {
  for (const auto& [id, stamp] : db.stamps()) {
    if (!stamp.error.empty() && !reasons.count(id)) {
      // The reason without the database and cell the stamp's error starts with.
      const std::size_t blob = stamp.error.find("near_chunks");
      reasons[id] = blob == std::string::npos ? stamp.error : stamp.error.substr(blob);
    }
    const bool bad = reasons.count(id) > 0;
    note_state(cells.state[id], bad ? "damaged" : stamp.status);
    if (stamp.status == "done" && !bad) s.cell_hashes[id] = stamp.content_hash;
    if (stamp.status == "failed" && !bad) {
      std::string error;
      try {
        const auto row = db.get_cell(id, false);
        error = row ? row->error : "";
      } catch (const std::exception& e) {
        error = e.what();
      }
      s.failed_cells.push_back({path, id, error.empty() ? "cell " + std::to_string(id) + ": (no message recorded)" : error});
    }
  }
}

// --repair: the damaged cells marked pending (under the database's lock).
void repair_database(const std::string& path, const std::map<std::int64_t, std::string>& reasons) {
  const CellDbLock lock(path, "repaired");
  std::vector<std::int64_t> ids;
  for (const auto& [id, reason] : reasons) ids.push_back(id);
  mark_cells_pending(path, ids);
  std::fprintf(stderr, "%s: %zu damaged cell(s) marked pending; rerun its bake to redo them\n", path.c_str(),
               ids.size());
}

// Adds one cell database: its totals, its configuration's cells and
// parameters, its damaged cells (printed; repaired with --repair).
void add_database(const std::string& path, const StatusOptions& opt, StatusTotals& s) {
  const bool check = opt.check || opt.repair;
  CellDb db(path, CellDb::Mode::read_only);
  const CellDbTotals t = db.totals();
  const std::string config_text = db.meta("config").value_or("");
  ConfigCells& cells = s.configs[config_text];
  if (!s.parameters.count(config_text))
    s.parameters[config_text] = parse_parameters(db.meta("store").value_or(""), config_text);
  cells.total = std::max(cells.total, meta_u64(db, "cells_total", 0));
  add_database_totals(db, t, s);
  std::map<std::int64_t, std::string> reasons;  // this database's damaged cells
  if (check) reasons = check_database(db, path, s);
  note_cell_states(db, path, reasons, cells, s);
  for (const auto& [id, reason] : reasons) {
    s.damaged.push_back({path, id, reason});
    std::fprintf(stderr, "%s: cell %lld: %s\n", path.c_str(), (long long)id, reason.c_str());
  }
  if (opt.repair && !reasons.empty()) repair_database(path, reasons);
  s.per_db.push_back({{"database", path},
                      {"cells_done", t.cells_done},
                      {"cells_failed", t.cells_failed},
                      {"cells_damaged", reasons.size()}});
}

// The configurations' cells counted once per id, and those not yet stored.
struct CellCounts {
  std::uint64_t total = 0, done = 0, failed = 0, bad = 0, pending = 0;
};

// Counts the cells and drops from the failed list the cells another database
// has done. Repaired cells are pending now; unrepaired damaged ones are
// neither done nor pending.
CellCounts count_cells(StatusTotals& s, bool repaired) {
  CellCounts n;
  for (const auto& [config, cells] : s.configs) {
    n.total += std::max<std::uint64_t>(cells.total, cells.state.size());
    for (const auto& [id, state] : cells.state) {
      n.done += state == "done";
      n.failed += state == "failed";
      n.bad += state == "damaged";
    }
  }
  // A cell another database has done is not failed (a shard rerun, a merge).
  std::erase_if(s.failed_cells, [&](const FailedCell& f) {
    for (const auto& [config, cells] : s.configs)
      if (const auto it = cells.state.find(f.id); it != cells.state.end() && it->second == "failed") return false;
    return true;
  });
  if (repaired) n.bad = 0;
  n.pending = n.total - std::min(n.total, n.done + n.failed + n.bad);
  return n;
}

// `status --json`: the counts, totals, databases, damaged and failed cells and bakes as one object.
void print_status_json(const StatusTotals& s, const CellCounts& n, const std::string& content_hash) {
  nlohmann::json j;
  j["cells_total"] = n.total;
  j["cells_done"] = n.done;
  j["cells_failed"] = n.failed;
  j["cells_damaged"] = n.bad;
  j["cells_pending"] = n.pending;
  j["stage_seconds"] = s.stage_seconds;
  j["content_hash"] = content_hash;
  j["bytes"] = s.bytes;
  j["bytes_by_kind"] = {{"colour", s.by_kind.colour},
                        {"mesh", s.by_kind.mesh},
                        {"near_list", s.by_kind.near_list},
                        {"far_geometry", s.by_kind.far_geometry}};
  j["far_triangles"] = s.far;
  j["far_geometry_triangles"] = s.far_geometry;
  j["far_geometry_levels"] = {{"rows", s.level_rows}, {"triangles", s.far_levels}};  // of those, simplified
  j["far_choice"] = {{"geometry_tiles", s.geometry_tiles}, {"face_tiles", s.face_tiles}, {"replaced_triangles", s.replaced}};
  j["samples"] = s.samples;
  j["delta_covered_pixels"] = s.delta_covered;
  j["delta_removed_pixels"] = s.delta_removed;
  j["databases"] = s.per_db;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& d : s.damaged) list.push_back({{"database", d.database}, {"cell", d.id}, {"reason", d.reason}});
  j["damaged"] = list;
  nlohmann::json meta_list = nlohmann::json::array();
  for (const auto& d : s.damaged_meta) meta_list.push_back({{"database", d.database}, {"key", d.key}, {"reason", d.reason}});
  j["damaged_meta"] = meta_list;
  nlohmann::json failed_list = nlohmann::json::array();
  for (const auto& f : s.failed_cells)
    failed_list.push_back({{"database", f.database}, {"cell", f.id}, {"error", f.error}});
  j["failed"] = failed_list;
  nlohmann::json bakes = nlohmann::json::array();
  for (const auto& [config, p] : s.parameters) bakes.push_back(parameters_json(p));
  j["bakes"] = bakes;
  std::printf("%s\n", j.dump(2).c_str());
}

// The failed cells, the first 20 of them listed (with their database when several were given).
void print_failed_cells(const std::vector<FailedCell>& failed_cells, bool several_databases) {
  constexpr std::size_t kShown = 20;
  std::printf("failed cells (%zu):\n", failed_cells.size());
  for (std::size_t i = 0; i < failed_cells.size() && i < kShown; ++i)
    std::printf("  %s%s%s\n", several_databases ? failed_cells[i].database.c_str() : "",
                several_databases ? ": " : "", failed_cells[i].error.c_str());  // the error names cell and stage
  if (failed_cells.size() > kShown)
    std::printf("  ... and %zu more (`cellbake status --json` lists them all)\n", failed_cells.size() - kShown);
  std::printf("  rerun the bake to retry them (done cells are skipped)\n");
}

// `status` for people: the counts, each bake's parameters, the failed cells,
// what is stored, the far choice, bytes and samples per cell, time per stage
// and the content hash.
void print_status_text(const StatusTotals& s, const CellCounts& n, const std::string& content_hash,
                       bool several_databases) {
  std::printf("cells: %llu total, %llu done, %llu failed, %llu pending", (unsigned long long)n.total,
              (unsigned long long)n.done, (unsigned long long)n.failed, (unsigned long long)n.pending);
  if (n.bad) std::printf(", %llu damaged", (unsigned long long)n.bad);
  std::printf("\n");
  for (const auto& [config, p] : s.parameters) print_parameters(p, verbose_output());
  if (!s.failed_cells.empty()) print_failed_cells(s.failed_cells, several_databases);
  std::printf("stored: %.1f MB, far field: %llu depth-mesh triangles, %llu exact geometry triangles",
              s.bytes / 1e6, (unsigned long long)s.far, (unsigned long long)s.far_geometry);
  if (s.level_rows > 0)
    std::printf(" (%llu of them in %llu simplified chunk levels)", (unsigned long long)s.far_levels,
                (unsigned long long)s.level_rows);
  std::printf("\n");
  if (s.face_tiles > 0)
    std::printf("far choice: %llu of %llu face tiles drawn as geometry (%.1f %%), replacing %llu depth-mesh "
                "triangles\n",
                (unsigned long long)s.geometry_tiles, (unsigned long long)s.face_tiles,
                100.0 * double(s.geometry_tiles) / double(s.face_tiles), (unsigned long long)s.replaced);
  if (s.by_kind.cells > 0) {
    const double k = 1e3 * double(s.by_kind.cells);
    std::printf("per done cell: %.1f KB colour, %.1f KB mesh, %.1f KB near list, %.1f KB far geometry\n",
                s.by_kind.colour / k, s.by_kind.mesh / k, s.by_kind.near_list / k, s.by_kind.far_geometry / k);
  }
  if (n.done > 0 && s.samples > 0)
    std::printf("samples: %.2f per done cell; delta scans: %.1f %% of their pixels removed (an ancestor holds them)\n",
                double(s.samples) / double(n.done),
                s.delta_covered ? 100.0 * double(s.delta_removed) / double(s.delta_covered) : 0.0);
  for (const auto& [k, v] : s.stage_seconds) std::printf("  %-11s %9.2f s\n", k.c_str(), v);
  std::printf("content hash: %s\n", content_hash.c_str());
}

// Cell databases given: their cells and totals summed, printed as JSON or
// text. With --check, throws after printing when cells or meta values are damaged.
void show_cell_database_status(const StatusOptions& opt) {
  StatusTotals totals;
  for (const auto& path : opt.dbs) add_database(path, opt, totals);
  const CellCounts counts = count_cells(totals, opt.repair);
  Hasher h;
  for (const auto& [id, hash] : totals.cell_hashes) h.u64(std::uint64_t(id)).text(hash);
  if (opt.json)
    print_status_json(totals, counts, h.hex());
  else
    print_status_text(totals, counts, h.hex(), opt.dbs.size() > 1);
  const bool check = opt.check || opt.repair;
  if (check && !opt.repair && !totals.damaged.empty())
    throw std::runtime_error(std::to_string(totals.damaged.size()) +
                             " damaged cell(s) (listed above); `cellbake status --repair` marks them pending");
  if (check && !totals.damaged_meta.empty())
    throw std::runtime_error(std::to_string(totals.damaged_meta.size()) +
                             " damaged meta value(s) (listed above): the database's parameters cannot be trusted; "
                             "rebake it");
}

}  // namespace

void add_status_command(CLI::App& app) {
  auto opt = std::make_shared<StatusOptions>();
  CLI::App* cmd = app.add_subcommand(
      "status", "Show the state of cell databases (one, or the shards of a bake), or what a geometry store holds");
  cmd->add_option("databases", opt->dbs,
                  "Cell database(s), several shards are summed; or geometry store(s): bounds, size, triangles, "
                  "up axis, sources")
      ->required();
  cmd->add_flag("--json", opt->json, "Machine-readable output");
  cmd->add_flag("--check", opt->check,
                "Recompute every cell's content hash from its rows and decode every blob; list damaged cells "
                "(exit 1 when there are any). On a geometry store: its content hash recomputed, the R-tree "
                "against the chunk rows, every chunk blob decoded");
  cmd->add_flag("--repair", opt->repair, "As --check, then mark the damaged cells pending (the next bake redoes them)");
  cmd->callback([opt] {
    std::size_t stores = 0;
    for (const auto& path : opt->dbs) stores += database_kind(path) == DatabaseKind::geometry_store;
    if (stores == 0) return show_cell_database_status(*opt);
    if (stores != opt->dbs.size()) throw std::invalid_argument("give either geometry stores or cell databases, not both");
    show_store_status(*opt);
  });
}

}  // namespace cellbake
