// Copying cells between cell databases, for merging the shards of a
// distributed bake: rows (cell, samples, faces) move SQLite to SQLite through
// ATTACH, without decoding blobs, each cell in its own transaction.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "storage/cell_check.h"
#include "storage/cell_db.h"

namespace cellbake {

struct CellCopyCounts {
  std::uint64_t copied = 0;     // cells added to the target or replacing a different row there
  std::uint64_t unchanged = 0;  // the target already held the same row (status, input and content hash)
  std::uint64_t kept_done = 0;  // the source's cell failed but the target's is done: the target's kept
};

// Copies every cell of `source` into `target`, one transaction per cell (a
// cell is wholly copied or not at all). A cell already present with the same
// status, input hash and content hash is left alone, so copying the same
// source twice changes nothing; a done cell is never replaced by a failed one;
// otherwise the source's row replaces the target's. Both databases must be of
// this cellbake's schema (CellDb checks on open). Metadata is not copied.
// Every cell to be copied is verified first (check_cell with `context`:
// content hash recomputed, blobs decoded, place in the grid and content
// against the store where the context has them); a damaged one throws
// std::runtime_error naming the source file and the cells, before anything is
// written. Other errors throw naming the source file too.
CellCopyCounts copy_cells(CellDb& target, const CellDb& source, const CellCheckContext& context = {});

// Every metadata entry whose key starts with `prefix` (key -> value; may be empty).
std::map<std::string, std::string> metas_with_prefix(const CellDb& db, const std::string& prefix);

}  // namespace cellbake
