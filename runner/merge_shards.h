// Merging the shard databases of a distributed bake (`cellbake merge`) into
// one cell database with the same content as a single-machine bake.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace cellbake {

struct MergeSummary {
  std::uint64_t shards_merged = 0;     // shard files read (including ones with no cells yet)
  std::vector<std::string> missing_shards;  // shard files that do not exist
  std::uint64_t cells_copied = 0, cells_unchanged = 0, cells_kept_done = 0;
  std::uint64_t cells_done = 0, cells_failed = 0;  // in the merged database afterwards
  std::uint64_t cells_total = 0;                   // the merged database's cells_total meta
  // When a shard is missing: ids of the cells of the configured regions that
  // are not in the merged database, in order (empty when nothing is missing).
  std::vector<std::int64_t> missing_cells;
};

// Merges `shards` into `out` (created if absent; merging into an existing
// merged database adds to it). Every shard, and `out` if it already holds
// cells, must come from the same geometry store and parameters (store_hash and
// config meta); otherwise throws std::runtime_error naming the shard and the
// difference, before anything is written. A missing shard file is reported
// through `warn` and skipped. Cells are copied one transaction each (see
// copy_cells): idempotent, and done cells are never replaced by failed ones.
// The merged cells_total meta is the configuration's cell count (from the
// regions in the config meta); when the config names no regions, the sum of
// the cells_selected of every shard ever merged into `out` (each shard
// counted once, by absolute path). Takes the output's bake lock (CellDbLock).
// Every cell is checked as `status --check` checks it (check_cell), but its
// face images are compared with the model only when `check_images` (it costs
// a low-resolution resample of the model per sample: on the 82 M plant more
// than the merge itself).
MergeSummary merge_shards(const std::filesystem::path& out, const std::vector<std::filesystem::path>& shards,
                          const std::function<void(const std::string&)>& warn, bool check_images = false);

// Formats sorted ids as a cell selection ("1-3,7,9-10"), the syntax --cells takes.
std::string format_cell_selection(const std::vector<std::int64_t>& ids);

}  // namespace cellbake
