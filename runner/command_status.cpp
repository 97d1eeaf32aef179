// `cellbake status DB... [--json]`: what is done, failed and pending, totals,
// time per stage and a content hash over every finished cell.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>

#include "runner/commands.h"
#include "stages/hashing.h"
#include "storage/cell_db.h"

namespace cellbake {

void add_status_command(CLI::App& app) {
  struct Options {
    std::vector<std::string> dbs;
    bool json = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("status", "Show the state of cell databases (one, or the shards of a bake)");
  cmd->add_option("databases", opt->dbs, "Cell database(s); several shards are summed")->required();
  cmd->add_flag("--json", opt->json, "Machine-readable output");
  cmd->callback([opt] {
    std::uint64_t total = 0, done = 0, failed = 0, bytes = 0, far = 0, samples = 0, delta_covered = 0, delta_removed = 0;
    std::map<std::string, double> stage_seconds;
    // Per-cell content hashes from every database, combined in id order, so a
    // merged database and its shards hash alike.
    std::map<std::int64_t, std::string> cell_hashes;
    nlohmann::json per_db = nlohmann::json::array();
    for (const auto& path : opt->dbs) {
      CellDb db(path, CellDb::Mode::read_only);
      const CellDbTotals t = db.totals();
      const std::uint64_t db_total = std::stoull(db.meta("cells_total").value_or("0"));
      total += std::max<std::uint64_t>(db_total, t.cells_done + t.cells_failed);
      done += t.cells_done;
      failed += t.cells_failed;
      bytes += t.bytes;
      far += t.far_triangles;
      samples += t.samples;
      delta_covered += t.delta_covered_pixels;
      delta_removed += t.delta_removed_pixels;
      for (const auto& [k, v] : t.stage_seconds) stage_seconds[k] += v;
      for (const auto& [id, stamp] : db.stamps())
        if (stamp.status == "done") cell_hashes[id] = stamp.content_hash;
      per_db.push_back({{"database", path}, {"cells_done", t.cells_done}, {"cells_failed", t.cells_failed}});
    }
    Hasher h;
    for (const auto& [id, hash] : cell_hashes) h.u64(std::uint64_t(id)).text(hash);
    const std::uint64_t pending = total - std::min(total, done + failed);
    if (opt->json) {
      nlohmann::json j;
      j["cells_total"] = total;
      j["cells_done"] = done;
      j["cells_failed"] = failed;
      j["cells_pending"] = pending;
      j["stage_seconds"] = stage_seconds;
      j["content_hash"] = h.hex();
      j["bytes"] = bytes;
      j["far_triangles"] = far;
      j["samples"] = samples;
      j["delta_covered_pixels"] = delta_covered;
      j["delta_removed_pixels"] = delta_removed;
      j["databases"] = per_db;
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("cells: %llu total, %llu done, %llu failed, %llu pending\n", (unsigned long long)total,
                (unsigned long long)done, (unsigned long long)failed, (unsigned long long)pending);
    std::printf("stored: %.1f MB, %llu far-field triangles\n", bytes / 1e6, (unsigned long long)far);
    if (done > 0 && samples > 0)
      std::printf("samples: %.2f per done cell; delta scans: %.1f %% of their pixels removed (an ancestor holds them)\n",
                  double(samples) / double(done),
                  delta_covered ? 100.0 * double(delta_removed) / double(delta_covered) : 0.0);
    for (const auto& [k, v] : stage_seconds) std::printf("  %-11s %9.2f s\n", k.c_str(), v);
    std::printf("content hash: %s\n", h.hex().c_str());
  });
}

}  // namespace cellbake
