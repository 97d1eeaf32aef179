// Integrity checks of a geometry store, beyond SQLite's own: `status --check`
// on a store (check_store: the content hash recomputed, the R*Tree against the
// chunk rows, every chunk blob decoded) and the cheap check a bake or verify
// runs before trusting a store (check_store_rows: the row counts ingest
// recorded in meta `rows`).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cellbake {

struct StoreProblem {
  std::int64_t chunk_id = 0;  // the chunk it is about; 0 when it is about the store as a whole
  std::string reason;         // e.g. "no R-tree entry", "content hash mismatch (...)"
};

// "chunk 12: no R-tree entry" / "content hash mismatch ...": the problem with
// what it is about.
std::string describe(const StoreProblem& problem);

// The full check: meta `rows` (when recorded) against the tables' row counts;
// meta `chunks` and `triangles` against the chunk rows; every chunk row has
// exactly one R-tree entry holding its bounds (float32, rounded outwards) and
// no R-tree entry names a missing chunk; every chunk blob decodes to the
// triangle and vertex counts of its row; the content hash recomputed from the
// rows (stored_content_hash, schema 2 stores) equals meta `content_hash`.
// Empty when the store is sound. Never throws for a damaged row; throws
// std::runtime_error naming the path when the file is not a geometry store.
std::vector<StoreProblem> check_store(const std::filesystem::path& store);

// The cheap check: each table's row count against meta `rows` (one count per
// table, no blob read). Stores written before meta `rows` existed have nothing
// to compare with and pass. Empty when sound; throws as check_store.
std::vector<StoreProblem> check_store_rows(const std::filesystem::path& store);

// Throws std::runtime_error naming the store and its first problems (and how
// to find all of them) unless check_store (`full`) or check_store_rows finds
// none. What `bake` and `verify` call before they read a store.
void require_sound_store(const std::filesystem::path& store, bool full);

// "" when the store's content hash `store_hash` is the one cell database
// `database` was baked from (`baked_store_hash`, its meta `store_hash`; an
// absent one is not compared), else a sentence naming both files and hashes:
// the cells' near lists and far geometry name chunks of another model.
std::string store_mismatch(const std::filesystem::path& database,
                           const std::optional<std::string>& baked_store_hash,
                           const std::filesystem::path& store, const std::string& store_hash);

}  // namespace cellbake
