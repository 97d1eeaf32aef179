#include "storage/cell_check.h"

#include <algorithm>
#include <exception>
#include <set>

#include <array>
#include <cmath>
#include <cstdio>

#include "stages/cube_map.h"
#include "stages/cull_box.h"
#include "stages/encode/encode.h"
#include "stages/encode/encode_triangle_list.h"
#include "stages/far/far_choice.h"
#include "storage/cell_content_hash.h"
#include "storage/chunk_codec.h"
#include "storage/far_geometry_check.h"
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

// Equal within rounding of the value's magnitude (bounds recomputed from the
// same doubles agree exactly; a tolerance keeps the check about damage).
bool close(double a, double b) { return a == b || std::fabs(a - b) <= 1e-9 * std::max({1.0, std::fabs(a), std::fabs(b)}); }
bool close(const Vec3d& a, const Vec3d& b) { return close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z); }
bool close(const Box3d& a, const Box3d& b) { return close(a.lo, b.lo) && close(a.hi, b.hi); }

std::string text(const Box3d& b) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g, %.9g)..(%.9g, %.9g, %.9g)", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
  return buf;
}

// The cell's region, grid indices and bounds against its place in the grid.
std::string check_place(const CellRow& row, const CellCheckContext& context) {
  if (!context.place) return "";
  const std::optional<CellPlace> place = context.place(row.id);
  if (!place) return "cell id " + std::to_string(row.id) + " is not in the configured grid";
  if (row.region != place->region || row.gx != place->gx || row.gy != place->gy || row.gz != place->gz)
    return "grid place region " + std::to_string(row.region) + " (" + std::to_string(row.gx) + ", " +
           std::to_string(row.gy) + ", " + std::to_string(row.gz) + ") is not the grid's region " +
           std::to_string(place->region) + " (" + std::to_string(place->gx) + ", " + std::to_string(place->gy) + ", " +
           std::to_string(place->gz) + ")";
  if (!close(row.bounds, place->bounds))
    return "bounds " + text(row.bounds) + " are not the grid's " + text(place->bounds) +
           " (a viewer would draw this cell elsewhere)";
  return "";
}

// Per face: recorded triangles, a grid-coded mesh coded for its own face, none
// wholly within a geometry tile, and the samples' triangles summing to the
// far-choice row's.
std::string check_faces_against_far_choice(const CellRow& row) {
  std::array<const FarChoiceRow*, kCubeFaces> choice{};
  for (const FarChoiceRow& c : row.far_choice) {
    if (c.face < 0 || c.face >= kCubeFaces) return "far choice row for face " + std::to_string(c.face) + " (0..5)";
    if (choice[std::size_t(c.face)]) return "two far choice rows for face " + std::to_string(c.face);
    choice[std::size_t(c.face)] = &c;
  }
  std::array<std::uint64_t, kCubeFaces> kept{};
  for (const SampleRow& s : row.samples)
    for (const FaceRow& f : s.faces) {
      const std::string at = "sample " + std::to_string(s.index) + " face " + std::to_string(f.face);
      FaceMesh mesh = decode_face_mesh(f.mesh);  // decoded once before: cannot throw here
      if (mesh.triangle_count() != f.triangles)
        return at + " mesh: " + std::to_string(mesh.triangle_count()) + " triangles, " + std::to_string(f.triangles) +
               " recorded";
      kept[std::size_t(f.face)] += f.triangles;
      // A grid-coded mesh (blob version 2) names its face in byte 5 and
      // decodes onto that face's pixel rays: a mesh of another face swapped
      // in says so. (Version 1 meshes carry no face; not checked.)
      if (f.mesh.size() > 5 && f.mesh[4] == 2 && f.mesh[5] != f.face)
        return at + " mesh: the mesh of face " + std::to_string(f.mesh[5]) + " (swapped between faces?)";
      if (const FarChoiceRow* c = choice[std::size_t(f.face)]; c && c->geometry_tiles != 0)
        if (const std::size_t inside = drop_geometry_tiles(mesh, c->geometry_tiles))
          return at + " mesh: " + std::to_string(inside) +
                 " triangles lie within the face's geometry tiles (the far choice row says geometry is drawn there)";
    }
  if (row.far_choice.empty()) return "";  // baked before the far choice, or nothing to draw
  for (int f = 0; f < kCubeFaces; ++f) {
    const std::uint64_t recorded = choice[std::size_t(f)] ? choice[std::size_t(f)]->tdm_triangles : 0;
    if (kept[std::size_t(f)] != recorded)
      return "face " + std::to_string(f) + ": the samples' meshes hold " + std::to_string(kept[std::size_t(f)]) +
             " triangles, its far choice row " + std::to_string(recorded);
  }
  return "";
}

// Far geometry rows against themselves: positive chunk ids, ordered finite
// bounds, triangles summing to the cell's figure.
std::string check_far_rows(const CellRow& row) {
  std::uint64_t triangles = 0;
  // Geometry tiles may draw nothing of the far field (all they see is near
  // chunks in the seam shell, seen on the 82 M plant): rows are needed only
  // where a face's tiles draw far triangles.
  bool geometry_tiles = false;
  for (const FarChoiceRow& c : row.far_choice) geometry_tiles |= c.geometry_tiles != 0 && c.geometry_triangles != 0;
  for (const FarGeometryRow& g : row.far_geometry) {
    const std::string at = "far geometry of chunk " + std::to_string(g.chunk_id);
    if (g.chunk_id <= 0) return at + ": chunk ids are positive";
    const Box3d& b = g.bounds;
    if (!is_finite(b.lo) || !is_finite(b.hi) || b.lo.x > b.hi.x || b.lo.y > b.hi.y || b.lo.z > b.hi.z)
      return at + ": bounds " + text(b) + " are inverted or not finite";
    if (g.whole && !g.geometry.empty()) return at + ": a whole chunk with a geometry blob";
    triangles += g.triangles;
  }
  if (triangles != row.far_geometry_triangles)
    return "far geometry rows hold " + std::to_string(triangles) + " triangles, the cell records " +
           std::to_string(row.far_geometry_triangles) + " (rows deleted or added)";
  if (geometry_tiles && row.far_geometry.empty())
    return "far choice draws far triangles in geometry tiles but the cell has no far geometry rows";
  return "";
}

// Far geometry against the store: chunks present, triangle numbers within
// them, bounds and origin those of the triangles named, levels the store
// lists with the row's triangle count.
std::string check_far_against_store(const CellRow& row, const ChunkSource& store) {
  for (const FarGeometryRow& g : row.far_geometry) {
    const std::string at = "far geometry of chunk " + std::to_string(g.chunk_id);
    std::shared_ptr<const Chunk> chunk;
    std::vector<ChunkLodRef> lods;
    try {
      chunk = store.load(g.chunk_id);
      if (g.level != 0) lods = store.lods(g.chunk_id);
    } catch (const std::exception& e) {
      return at + ": " + e.what();
    }
    if (std::string problem = far_geometry_problem(g, *chunk, lods); !problem.empty()) return problem;
  }
  return "";
}

// The near list against the cull box's content in the store.
std::string check_near_list(const CellRow& row, const Box3d& bounds, const ChunkSource& store) {
  CullBoxResult expected;
  try {
    expected = near_field_at(bounds.center(), row.cull_half_size, store);
  } catch (const std::exception& e) {
    return std::string("near list: the cull box cannot be evaluated in the store: ") + e.what();
  }
  // Chunks at the cube's boundary may differ by rounding between the bake's
  // search and this evaluation: the list must name only chunks the cube
  // meets and every chunk lying wholly within it.
  if (row.near_chunks.empty() && !expected.near_field.empty())
    return "near list is empty, the cull box meets " + std::to_string(expected.near_field.size()) +
           " chunks in the store";
  std::set<std::int64_t> meets, listed;
  for (const NearChunk& e : expected.near_field) meets.insert(e.chunk_id);
  std::uint64_t sum = 0;
  for (const NearChunkRow& n : row.near_chunks) {
    if (!meets.count(n.chunk_id))
      return "near list names chunk " + std::to_string(n.chunk_id) + ", which the cull box does not meet in the store";
    listed.insert(n.chunk_id);
    sum += n.triangles;
  }
  if (sum != row.near_triangles)
    return "near list holds " + std::to_string(sum) + " triangles, the cell records " + std::to_string(row.near_triangles);
  for (const NearChunk& e : expected.near_field)
    if (e.whole && !listed.count(e.chunk_id))
      return "near list lacks chunk " + std::to_string(e.chunk_id) + " (" + std::to_string(e.triangles) +
             " triangles), which lies wholly within the cull box";
  return "";
}

}  // namespace

std::string check_cell(const CellDb& db, std::int64_t id, const CellCheckContext& context) {
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
      // Another valid image put in its place (a PNG of zeros for an AVIF face) draws wrong.
      if (const std::string format = encoded_image_format(f.image); format != f.image_format)
        return face + " image: a " + format + " image, but the face's row says " + f.image_format;
      if (!(image.width == 1 && image.height == 1 && f.triangles == 0)) {
        if (face_size == 0) face_size = image.width;  // unknown: the first face's size holds for the rest
        if (image.width != face_size || image.height != face_size)
          return face + " image: " + std::to_string(image.width) + "x" + std::to_string(image.height) + ", not " +
                 std::to_string(face_size) + "x" + std::to_string(face_size);
      }
    }
  }
  for (const auto& g : row->far_geometry) {
    if (std::string problem = far_geometry_level_problem(g); !problem.empty()) return problem;
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
  // What the hash cannot tell: columns outside it, and content a hostile or
  // buggy shard restamped.
  try {
    if (std::string problem = check_place(*row, context); !problem.empty()) return problem;
    if (std::string problem = check_faces_against_far_choice(*row); !problem.empty()) return problem;
    if (std::string problem = check_far_rows(*row); !problem.empty()) return problem;
    if (context.store) {
      if (std::string problem = check_far_against_store(*row, *context.store); !problem.empty()) return problem;
      const std::optional<CellPlace> place = context.place ? context.place(row->id) : std::nullopt;
      if (std::string problem = check_near_list(*row, place ? place->bounds : row->bounds, *context.store);
          !problem.empty())
        return problem;
    }
    if (context.resample)
      if (std::string problem = check_face_images_against_model(*row, context.resample); !problem.empty())
        return problem;
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::vector<CellProblem> check_cells(const CellDb& db, const CellCheckContext& context) {
  std::vector<CellProblem> problems;
  for (std::int64_t id : db.cell_ids())
    if (std::string reason = check_cell(db, id, context); !reason.empty()) problems.push_back({id, std::move(reason)});
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
