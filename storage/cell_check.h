// Integrity checks of stored cells, beyond SQLite's own: each done cell's
// content hash recomputed from its rows (cell_content_hash, as the bake
// computed it), every blob decoded (near_chunks, face images, face meshes,
// far geometry), the columns outside the hash checked against what
// determines them (the cell's place in the grid), and the content checked
// against itself and the geometry store it was baked from (near list = the
// cull box's content, far geometry within its chunks, per-face figures). Used
// by `status --check` / `--repair` and by `merge` on incoming cells.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "stages/chunk_source.h"
#include "storage/cell_db.h"
#include "storage/face_image_check.h"

namespace cellbake {

struct CellProblem {
  std::int64_t id = 0;
  std::string reason;  // e.g. "sample 0 face 3 mesh: face mesh blob: ..." or "content hash mismatch ..."
};

// Where a cell belongs in its configuration's grid (pipeline/cell_grid.h
// computes it from the database's meta `config`).
struct CellPlace {
  int region = 0;
  int gx = 0, gy = 0, gz = 0;
  Box3d bounds;
};

// What check_cell compares a cell with beyond its own rows; each part is
// optional (a default context checks rows, blobs and hash only).
struct CellCheckContext {
  // The cell's place in the grid by id; nullopt: the id is not in the grid.
  // Empty function: places unknown, not checked.
  std::function<std::optional<CellPlace>(std::int64_t id)> place;
  // The geometry store the database was baked from (its content hash equal
  // to meta `store_hash`; any ChunkSource in tests), or null: the near list
  // is then not recomputed and far geometry is not compared with the chunks
  // and levels it names.
  const ChunkSource* store = nullptr;
  // The model resampled as the cell's far field shows it (pipeline/
  // cell_database_check.h builds one from the config and the store), or
  // empty: face images are decoded and sized, not compared with the model.
  FarFieldResampler resample;
};

// Checks cell `id` of `db`: empty when it is sound (or failed: failed cells
// have no content to check), else why not. A done cell must have six faces
// (0..5) per sample, decodable near_chunks, images and meshes, and rows that
// hash to its stored content_hash; each face mesh's triangles as recorded,
// a grid-coded one (blob version 2) coded for its own face, none wholly within the
// face's geometry tiles, and per face the samples' triangles summing to the
// far-choice row's; far geometry rows naming positive chunk ids, ordered
// bounds, triangles summing to the cell's far_geometry_triangles, levels
// 0..kMaxFarGeometryLevel, a level >= 1 whole with no blob. With a
// place: region, grid indices and bounds as the grid has them. With a store:
// the near list against near_field_at(centre, cull_half_size) of the store
// (non-empty when the cube meets chunks, only chunks it meets, every chunk
// wholly within it, triangles summing to near_triangles),
// far geometry naming chunks the store holds, triangle numbers within them and
// bounds and origin equal to those of the triangles they name, a level >= 1
// one the store lists for the chunk (ChunkSource::lods) with the row's
// triangle count and the chunk's bounds. With a resampler: every face image
// against the model (check_face_images_against_model). Never throws
// for a damaged row; SQLite errors (an unreadable file) still throw.
std::string check_cell(const CellDb& db, std::int64_t id, const CellCheckContext& context = {});

// check_cell over every cell of `db` in id order; the damaged ones.
std::vector<CellProblem> check_cells(const CellDb& db, const CellCheckContext& context = {});

// Removes the cells `ids` (row, samples, faces) from the cell database at
// `path` in one transaction, so they count as pending and the next bake
// redoes them. Ids not present are ignored.
void mark_cells_pending(const std::filesystem::path& path, const std::vector<std::int64_t>& ids);

}  // namespace cellbake
