// Integrity checks of stored cells, beyond SQLite's own: each done cell's
// content hash recomputed from its rows (cell_content_hash, as the bake
// computed it) and every blob decoded (near_chunks, face images, face
// meshes). Used by `status --check` / `--repair` and by `merge` on incoming
// cells.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "storage/cell_db.h"

namespace cellbake {

struct CellProblem {
  std::int64_t id = 0;
  std::string reason;  // e.g. "sample 0 face 3 mesh: face mesh blob: ..." or "content hash mismatch ..."
};

// Checks cell `id` of `db`: empty when it is sound (or failed: failed cells
// have no content to check), else why not. A done cell must have six faces
// (0..5) per sample, decodable near_chunks, images and meshes, and rows that
// hash to its stored content_hash. Never throws for a
// damaged row; SQLite errors (an unreadable file) still throw.
std::string check_cell(const CellDb& db, std::int64_t id);

// check_cell over every cell of `db` in id order; the damaged ones.
std::vector<CellProblem> check_cells(const CellDb& db);

// Removes the cells `ids` (row, samples, faces) from the cell database at
// `path` in one transaction, so they count as pending and the next bake
// redoes them. Ids not present are ignored.
void mark_cells_pending(const std::filesystem::path& path, const std::vector<std::int64_t>& ids);

}  // namespace cellbake
