#include "storage/cell_check.h"

#include <algorithm>
#include <exception>
#include <set>

#include "stages/encode.h"
#include "storage/cell_content_hash.h"
#include "stages/encode_triangle_list.h"
#include "storage/chunk_codec.h"
#include "storage/sqlite_db.h"

namespace cellbake {
namespace {

// The face size the cells were baked at (the `sample.face_size=N` line of meta
// `config`), or 0 when the database does not say (unknown: faces are then
// only compared with each other).
int baked_face_size(const CellDb& db) {
  const std::string config = db.meta("config").value_or("");
  const std::string key = "sample.face_size=";
  std::size_t at = config.rfind("\n" + key);
  at = at != std::string::npos ? at + 1 : config.rfind(key, 0);
  if (at == std::string::npos) return 0;
  const std::size_t from = at + key.size(), end = std::min(config.find('\n', from), config.size());
  int size = 0;
  for (std::size_t i = from; i < end; ++i) {
    if (config[i] < '0' || config[i] > '9' || size > 100000) return 0;
    size = size * 10 + (config[i] - '0');
  }
  return end > from ? size : 0;
}

}  // namespace

std::string check_cell(const CellDb& db, std::int64_t id) {
  std::optional<CellRow> row;
  try {
    row = db.get_cell(id, true);
  } catch (const std::exception& e) {
    return e.what();
  }
  if (!row) return "not in the database";
  if (row->status == "failed") return "";
  if (row->status != "done") return "unknown status '" + row->status + "'";
  // Face images are face_size x face_size; a face without triangles holds none
  // (kNoFaceImage) or, baked before encode version 4, a 1 x 1 one.
  int face_size = baked_face_size(db);
  for (const auto& s : row->samples) {
    const std::string at = "sample " + std::to_string(s.index);
    std::set<int> faces;
    for (const auto& f : s.faces) faces.insert(f.face);
    if (s.faces.size() != 6 || faces.size() != 6 || *faces.begin() != 0 || *faces.rbegin() != 5)
      return at + " has " + std::to_string(s.faces.size()) + " faces (6 expected, one per cube face)";
    for (const auto& f : s.faces) {
      const std::string face = at + " face " + std::to_string(f.face);
      if (f.image_format == kNoFaceImage) {
        if (!f.image.empty()) return face + ": an image blob for a face that stores none";
        if (f.triangles != 0) return face + ": " + std::to_string(f.triangles) + " triangles but no image";
      }
      try {
        decode_face_mesh(f.mesh);
      } catch (const std::exception& e) {
        return face + " mesh: " + e.what();
      }
      if (f.image_format == kNoFaceImage) continue;
      DecodedImage image;
      try {
        image = decode_image(f.image);
      } catch (const std::exception& e) {
        return face + " image: " + e.what();
      }
      if (!(image.width == 1 && image.height == 1 && f.triangles == 0)) {
        if (face_size == 0) face_size = image.width;  // unknown: the first face's size holds for the rest
        if (image.width != face_size || image.height != face_size)
          return face + " image: " + std::to_string(image.width) + "x" + std::to_string(image.height) + ", not " +
                 std::to_string(face_size) + "x" + std::to_string(face_size);
      }
    }
  }
  for (const auto& g : row->far_geometry) {
    if (g.whole) continue;
    try {
      std::size_t triangles = 0;
      if (is_triangle_list_blob(g.geometry)) {
        triangles = decode_triangle_list(g.geometry).size();
      } else {  // a chunk blob of its own (cells baked before far_choice version 3)
        Chunk chunk;
        decode_chunk_blob(g.geometry.data(), g.geometry.size(), chunk);
        triangles = chunk.triangle_count();
      }
      if (triangles != g.triangles)
        return "far geometry of chunk " + std::to_string(g.chunk_id) + ": " + std::to_string(triangles) +
               " triangles, " + std::to_string(g.triangles) + " recorded";
    } catch (const std::exception& e) {
      return "far geometry of chunk " + std::to_string(g.chunk_id) + ": " + e.what();
    }
  }
  const std::string hash = cell_content_hash(*row);
  if (hash != row->content_hash)
    return "content hash mismatch (stored " + row->content_hash + ", its rows hash to " + hash + ")";
  return "";
}

std::vector<CellProblem> check_cells(const CellDb& db) {
  std::vector<CellProblem> problems;
  for (std::int64_t id : db.cell_ids())
    if (std::string reason = check_cell(db, id); !reason.empty()) problems.push_back({id, std::move(reason)});
  return problems;
}

void mark_cells_pending(const std::filesystem::path& path, const std::vector<std::int64_t>& ids) {
  SqliteDb db(path, SqliteDb::Mode::read_write_create);
  db.exec("PRAGMA foreign_keys=ON");  // as CellDb: every table of a cell's rows cascades from cells
  SqliteTransaction tx(db);
  SqliteStatement cells(db, "DELETE FROM cells WHERE id=?");
  for (std::int64_t id : ids) cells.bind(1, id).run();
  tx.commit();
}

}  // namespace cellbake
