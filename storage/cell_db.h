// The cell database: one row per baked view cell with its near-field list,
// panoramic samples and encoded far-field faces. Every cell is written in one
// transaction (wholly present or absent), WAL mode, versioned schema with
// migrations. Schema and example queries: docs/database.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

class SqliteDb;

struct NearChunkRow {
  std::int64_t chunk_id = 0;
  std::uint32_t triangles = 0;
  bool whole = false;
};

// The image format of a face without triangles (nothing of it is drawn): its
// image blob is empty. Cells baked before encode version 4 hold a 1 x 1 image.
inline constexpr const char* kNoFaceImage = "none";

struct FaceRow {
  int face = 0;                      // 0..5, cube_map.h order
  std::string image_format;          // "jpeg" | "webp" | "png" | "avif" | "jxl"; kNoFaceImage: none stored
  std::vector<std::uint8_t> image;   // encoded colour image (empty for kNoFaceImage)
  std::vector<std::uint8_t> mesh;    // encoded FaceMesh (stages/encode/encode.h)
  std::uint32_t triangles = 0;
  double boundary_error_px = 0;         // measured max screen-space movement of outlines (silhouettes, skins, borders)
  double depth_error = 0;            // achieved max relative depth error
};

struct SampleRow {
  int index = 0;    // the order the sample was taken in (0 = first of the initial set)
  Vec3d eye;
  int parent = -1;  // dependency-tree parent sample (-1 = root, the intra scan)
  double void_after = -1;  // worst best-next-view candidate's void fraction once this sample was taken (-1: not measured)
  std::uint64_t covered_pixels = 0;  // pixels with a surface before redundant-pixel removal
  std::uint64_t removed_pixels = 0;  // of those, removed because an ancestor holds them
  double seconds = 0;                // bake seconds spent on this sample (render, void search, mesh, simplify, encode)
  std::vector<FaceRow> faces;
};

// How one cube face's far field is drawn (issue #13): which of its
// kFarTiles x kFarTiles tiles draw exact far geometry (the cell's far_chunks)
// instead of textured depth meshes, with the figures the choice compared.
struct FarChoiceRow {
  int face = 0;                         // 0..5, cube_map.h order
  std::uint32_t geometry_tiles = 0;     // bit (row * 4 + column) set: the tile draws geometry
  std::uint64_t tdm_triangles = 0;      // depth-mesh triangles of this face kept, over all samples
  std::uint64_t replaced_triangles = 0; // depth-mesh triangles dropped because geometry covers their tile
  std::uint64_t geometry_triangles = 0; // triangles of the far chunks this face's geometry tiles need
};

// The highest simplified level a far geometry row may name (issue #35): the
// viewer's GPU cache id of a level (viewer/decoded_cell.h lod_cache_id) holds
// it in 4 bits; check_cell and decode_cell refuse rows beyond it.
inline constexpr int kMaxFarGeometryLevel = 15;

// Exact far geometry of a cell (issue #13): one source chunk, whole (drawn
// from the geometry store) or the triangles of it the samples saw, stored
// as a chunk blob (storage/chunk_codec.h) with its origin and bounds.
struct FarGeometryRow {
  std::int64_t chunk_id = 0;
  std::uint32_t triangles = 0;
  bool whole = false;
  // 0: the chunk itself (whole, or the triangles `geometry` lists); >= 1: the
  // store's simplified level of the whole chunk (whole is true, `triangles`
  // its triangle count; ChunkSource::load_lod), at most kMaxFarGeometryLevel.
  int level = 0;
  Vec3d origin;
  Box3d bounds;
  std::vector<std::uint8_t> geometry;  // empty when whole
};

struct CellRow {
  std::int64_t id = 0;
  int region = 0;
  int gx = 0, gy = 0, gz = 0;
  Box3d bounds;
  std::string status;  // "done" | "failed"
  std::string error;   // failure message naming cell and stage
  std::string input_hash;    // stage versions + parameters + store content for this cell
  std::string cull_hash;     // the part of input_hash the cull-box stage depends on
  std::string content_hash;  // over the cell's content (not timings)
  double cull_half_size = 0;
  std::uint64_t near_triangles = 0;
  std::vector<NearChunkRow> near_chunks;
  std::uint64_t far_triangles = 0;          // depth-mesh triangles over all samples and faces
  std::vector<FarGeometryRow> far_geometry; // exact far geometry drawn instead of depth meshes, by chunk id
  std::uint64_t far_geometry_triangles = 0; // its triangles
  std::vector<FarChoiceRow> far_choice;     // per face (empty: every tile draws depth meshes)
  std::uint64_t bytes = 0;
  double max_boundary_error_px = 0;
  double max_depth_error = 0;
  std::map<std::string, double> stage_seconds;
  std::vector<SampleRow> samples;
};

// A cell's identity and stored hashes, for resume decisions without loading blobs.
struct CellStamp {
  std::int64_t id = 0;
  std::string status, input_hash, cull_hash, content_hash;
  double cull_half_size = 0;
  std::vector<NearChunkRow> near_chunks;
  std::uint64_t near_triangles = 0;
  std::string error;  // non-empty when the row's near_chunks blob is unreadable (names database and cell)
};

struct CellDbTotals {
  std::uint64_t cells_done = 0, cells_failed = 0;
  std::map<std::string, double> stage_seconds;
  std::uint64_t bytes = 0, far_triangles = 0, near_triangles = 0;
  std::string content_hash;  // over every done cell's content_hash in id order
  std::uint64_t samples = 0;                 // panoramic samples over all cells
  std::uint64_t delta_covered_pixels = 0;    // pixels with a surface in delta scans (samples with a parent)
  std::uint64_t delta_removed_pixels = 0;    // of those, removed because an ancestor holds them
  // The far field's choice (issue #13) over done cells: exact far geometry
  // triangles stored, face tiles drawn as geometry of the face tiles with a
  // recorded choice (faces with anything to draw), and the depth-mesh
  // triangles the geometry replaced.
  std::uint64_t far_geometry_triangles = 0, geometry_tiles = 0, face_tiles = 0, replaced_triangles = 0;
  // Of far_geometry_triangles, those of rows drawing a simplified level of
  // their chunk (issue #35; schema version 5), and how many such rows.
  std::uint64_t far_level_triangles = 0, far_level_rows = 0;
};

// Stored bytes by kind over the done cells (issue #16): encoded colour images,
// encoded face meshes, near-field lists.
struct CellDbBytes {
  std::uint64_t cells = 0, colour = 0, mesh = 0, near_list = 0;
  std::uint64_t far_geometry = 0;  // exact far geometry blobs (issue #13)
};

class CellDb {
 public:
  enum class Mode { read_only, read_write };
  // Opens or creates (read_write) the database, applying migrations.
  CellDb(const std::filesystem::path& path, Mode mode);
  ~CellDb();

  // Key/value metadata (e.g. "config", "store_hash").
  void set_meta(const std::string& key, const std::string& value);
  std::optional<std::string> meta(const std::string& key) const;

  // Replaces the cell (and its samples and faces) in one transaction.
  void put_cell(const CellRow& cell);
  // Every cell's stamp; a row with an unreadable near_chunks blob gets `error`
  // set instead of throwing, so one damaged cell never hides the others.
  std::map<std::int64_t, CellStamp> stamps() const;
  // The cell, or nullopt when absent. Throws std::runtime_error naming the
  // database and cell when a stored blob (near_chunks) is unreadable.
  std::optional<CellRow> get_cell(std::int64_t id, bool with_blobs = true) const;
  std::vector<std::int64_t> cell_ids() const;
  CellDbTotals totals() const;
  // Sums of length(image), length(mesh) over the done cells' faces and of
  // length(near_chunks) over the done cells; one read-only query each.
  CellDbBytes bytes_by_kind() const;
  // PRAGMA integrity_check == "ok".
  bool integrity_ok() const;
  const std::filesystem::path& path() const;
  // The URI that ATTACHes this database read-only as this connection reads it
  // (SqliteDb::attach_uri: immutable in a read-only folder).
  std::string attach_uri() const;
  // The schema version of the open file (read-only opens may see an older one).
  int schema_version() const { return schema_version_; }

 private:
  std::unique_ptr<SqliteDb> db_;
  int schema_version_ = 0;
};

// Packs / unpacks a near-field list (validated; throws std::runtime_error on bad bytes).
std::vector<std::uint8_t> pack_near_chunks(const std::vector<NearChunkRow>& rows);
std::vector<NearChunkRow> unpack_near_chunks(const std::uint8_t* data, std::size_t size);

}  // namespace cellbake
