#include "runner/merge_shards.h"

#include <cstdio>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "pipeline/cell_grid.h"
#include "storage/cell_db.h"
#include "storage/cell_db_lock.h"
#include "pipeline/cell_database_check.h"
#include "storage/cell_db_merge.h"
#include "storage/meta_values.h"

namespace cellbake {
namespace {

constexpr const char* kMergedShardPrefix = "merged_shard:";

struct ShardInput {
  std::filesystem::path path;
  std::unique_ptr<CellDb> db;
  std::optional<std::string> store_hash, config;
  std::uint64_t cells_total = 0, rows = 0;  // cells_total: the cells this shard's bake was given
};

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The first line where two config descriptions differ, as "'a' vs 'b'".
std::string first_difference(const std::string& a, const std::string& b) {
  const auto la = lines_of(a), lb = lines_of(b);
  for (std::size_t i = 0; i < std::max(la.size(), lb.size()); ++i) {
    const std::string x = i < la.size() ? la[i] : "(nothing)", y = i < lb.size() ? lb[i] : "(nothing)";
    if (x != y) return "'" + x + "' vs '" + y + "'";
  }
  return "(no line differs)";
}

// The cells of the regions named in a `config` meta (describe_bake_config's
// "cells.size=" and "region=" lines); nullopt when it names none.
std::optional<std::vector<CellSpec>> cells_of_config_meta(const std::string& config) {
  double cell_size = 0;
  std::vector<Box3d> regions;
  for (const auto& line : lines_of(config)) {
    if (line.rfind("cells.size=", 0) == 0) cell_size = parse_meta_double("config", "cells.size", line.substr(11));
    if (line.rfind("region=", 0) == 0) {
      Box3d b;
      if (std::sscanf(line.c_str() + 7, "%lf,%lf,%lf,%lf,%lf,%lf", &b.lo.x, &b.lo.y, &b.lo.z, &b.hi.x, &b.hi.y,
                      &b.hi.z) == 6)
        regions.push_back(b);
    }
  }
  if (cell_size <= 0 || regions.empty()) return std::nullopt;
  return enumerate_cells(regions, cell_size);
}

// Opens a shard and reads what the compatibility check needs; nullopt when the file does not exist.
std::optional<ShardInput> open_shard(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) return std::nullopt;
  ShardInput s;
  s.path = path;
  s.db = std::make_unique<CellDb>(path, CellDb::Mode::read_only);
  s.store_hash = s.db->meta("store_hash");
  s.config = s.db->meta("config");
  s.rows = s.db->cell_ids().size();
  // A shard's own cells: `cells_selected` (older bakes wrote that count as cells_total).
  s.cells_total = meta_u64(*s.db, "cells_selected", meta_u64(*s.db, "cells_total", s.rows));
  return s;
}

// Throws unless `s` was baked from the same store and parameters as the reference.
void check_compatible(const ShardInput& s, const std::string& ref_name, const std::string& ref_store_hash,
                      const std::string& ref_config) {
  if (*s.store_hash != ref_store_hash)
    throw std::runtime_error(s.path.string() + ": baked from a different geometry store than " + ref_name +
                             " (store_hash " + *s.store_hash + " vs " + ref_store_hash + "); refusing to merge");
  if (s.config.value_or("") != ref_config)
    throw std::runtime_error(s.path.string() + ": baked with different parameters than " + ref_name + " (" +
                             first_difference(s.config.value_or(""), ref_config) + "); refusing to merge");
}

}  // namespace

std::string format_cell_selection(const std::vector<std::int64_t>& ids) {
  std::string out;
  for (std::size_t i = 0; i < ids.size();) {
    std::size_t j = i;
    while (j + 1 < ids.size() && ids[j + 1] == ids[j] + 1) ++j;
    if (!out.empty()) out += ",";
    out += std::to_string(ids[i]);
    if (j > i) out += "-" + std::to_string(ids[j]);
    i = j + 1;
  }
  return out;
}

MergeSummary merge_shards(const std::filesystem::path& out, const std::vector<std::filesystem::path>& shards,
                          const std::function<void(const std::string&)>& warn, bool check_images) {
  MergeSummary summary;
  const auto out_key = std::filesystem::weakly_canonical(out);
  std::vector<ShardInput> inputs;
  for (const auto& path : shards) {
    if (std::filesystem::weakly_canonical(path) == out_key)
      throw std::runtime_error(path.string() + ": is the output database; cannot merge a database into itself");
    auto s = open_shard(path);
    if (!s) {
      warn(path.string() + ": shard database does not exist; merging the others (its cells will be missing)");
      summary.missing_shards.push_back(path.string());
      continue;
    }
    if (!s->store_hash) {
      if (s->rows > 0) throw std::runtime_error(path.string() + ": holds cells but no store_hash meta; not a bake shard");
      warn(path.string() + ": has no cells yet (its bake had not started); skipped");
      summary.missing_shards.push_back(path.string());
      continue;
    }
    inputs.push_back(std::move(*s));
  }

  if (inputs.empty() && !std::filesystem::exists(out))
    throw std::runtime_error("none of the " + std::to_string(shards.size()) + " shard database(s) has cells to merge");

  // The reference: the output's own meta when it already holds a merge, else the first shard.
  std::string ref_name, ref_store_hash, ref_config;
  if (std::filesystem::exists(out)) {
    std::optional<CellDb> existing;
    try {
      existing.emplace(out, CellDb::Mode::read_only);
    } catch (const std::exception&) {
      // No cell schema yet (a merge killed before it committed one, or not
      // ours at all): the read-write open below adopts an empty file and
      // refuses anything else.
    }
    if (auto h = existing ? existing->meta("store_hash") : std::nullopt) {
      ref_name = out.string();
      ref_store_hash = *h;
      ref_config = existing->meta("config").value_or("");
    }
  }
  if (ref_name.empty() && !inputs.empty()) {
    ref_name = inputs.front().path.string();
    ref_store_hash = *inputs.front().store_hash;
    ref_config = inputs.front().config.value_or("");
  }
  for (const auto& s : inputs) {
    check_compatible(s, ref_name, ref_store_hash, ref_config);
    const std::vector<MetaProblem> problems = check_database_meta(*s.db);
    if (!problems.empty())
      throw std::runtime_error(s.path.string() + ": meta '" + problems.front().key + "': " + problems.front().reason +
                               (problems.size() > 1 ? " (and " + std::to_string(problems.size() - 1) + " more)" : "") +
                               "; refusing to merge this shard");
  }

  if (!out.parent_path().empty()) std::filesystem::create_directories(std::filesystem::absolute(out).parent_path());
  CellDb merged(out, CellDb::Mode::read_write);
  const CellDbLock lock(out, "merged into");  // no bake or other merge writes it meanwhile
  if (!inputs.empty() && !merged.meta("store_hash")) {
    const CellDb& first = *inputs.front().db;
    for (const char* key : {"store", "store_hash", "config", "up", "cell_size"})
      if (auto v = first.meta(key)) merged.set_meta(key, *v);
  }
  for (auto& s : inputs) {
    // Each shard's cells checked against their grid places and the store they were baked from.
    CellCheckSetup setup = cell_check_setup(*s.db);
    if (!setup.note.empty()) warn(s.path.string() + ": " + setup.note);
    if (!check_images) setup.context.resample = {};
    const CellCopyCounts c = copy_cells(merged, *s.db, setup.context);
    summary.cells_copied += c.copied;
    summary.cells_unchanged += c.unchanged;
    summary.cells_kept_done += c.kept_done;
    ++summary.shards_merged;
    merged.set_meta(kMergedShardPrefix + std::filesystem::absolute(s.path).lexically_normal().string(),
                    std::to_string(s.cells_total));
    if (s.rows < s.cells_total)
      warn(s.path.string() + ": " + std::to_string(s.cells_total - s.rows) + " of " + std::to_string(s.cells_total) +
           " cells not baked yet (rerun its bake to finish them)");
  }
  // The configuration's cell count, as a bake writes it; databases whose
  // config names no regions fall back to the sum over the merged shards.
  const auto config = merged.meta("config");
  const auto grid = config ? cells_of_config_meta(*config) : std::nullopt;
  if (grid) {
    summary.cells_total = grid->size();
  } else {
    for (const auto& [key, value] : metas_with_prefix(merged, kMergedShardPrefix))
      summary.cells_total += parse_meta_u64(out, key, value);
  }
  merged.set_meta("cells_total", std::to_string(summary.cells_total));

  const CellDbTotals t = merged.totals();
  summary.cells_done = t.cells_done;
  summary.cells_failed = t.cells_failed;
  if (!summary.missing_shards.empty()) {
    if (grid) {
      const auto present_ids = merged.cell_ids();
      const std::set<std::int64_t> present(present_ids.begin(), present_ids.end());
      for (const auto& c : *grid)
        if (!present.count(c.id)) summary.missing_cells.push_back(c.id);
      if (!summary.missing_cells.empty())
        warn(out.string() + ": " + std::to_string(summary.missing_cells.size()) + " of the " +
             std::to_string(grid->size()) + " cells of the configured regions are not in it: " +
             format_cell_selection(summary.missing_cells));
    } else {
      warn(out.string() + ": cannot tell which cells the missing shard(s) held");
    }
  }
  return summary;
}

}  // namespace cellbake
