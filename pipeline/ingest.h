// Ingest: reads model files, drops degenerate and duplicate triangles (counted),
// splits the rest into spatially coherent chunks and writes a geometry store.
// Textures the materials name are decoded (pipeline/texture_import.h), capped
// in size and stored inside the store, so a bake needs nothing else; one that
// cannot be read is a counted warning and its material keeps its colour.
// Memory is bounded: triangles (sizeof(Triangle), ~150 bytes) stay in memory up to a budget
// and then go to a temporary spill file; only 40-byte sort keys per triangle
// are always held in memory.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/readers/isolated_read.h"
#include "stages/chunk_lod.h"
#include "stages/geometry.h"
#include "stages/model_analysis/up_axis_from_geometry.h"

namespace cellbake {

// Runs fn(i) for i in [0, n), possibly in parallel; the runner supplies a TBB
// implementation, tests may pass a serial one. Results must not depend on it.
using ParallelFor = std::function<void(std::size_t n, const std::function<void(std::size_t)>& fn)>;

// Reports progress: phase name, amount done and total (0 = unknown); the last call is phase "done".
using ProgressCallback = std::function<void(const std::string& phase, std::uint64_t done, std::uint64_t total)>;

struct IngestParams {
  std::size_t max_chunk_triangles = 4096;  // chunks hold (max/2, max] triangles, except runs of duplicates
  Vec3d translate{0, 0, 0};                // added to every coordinate (tests, survey offsets)
  std::string units = "m";
  std::size_t memory_budget_bytes = std::size_t(6) << 30;  // triangles beyond this go to a spill file
  std::filesystem::path temp_dir;          // for the spill file; empty = next to the store
  int max_texture_size = 2048;             // textures are halved until both sides fit (>= 1)
  // Files a model names (mtllib, map_Kd, glTF buffers and images) are read only
  // inside the model's folder and subfolders unless this is set; a refused one
  // is a warning (input_warnings, texture_warnings), or an error when the
  // model cannot load without it (pipeline/readers/contained_paths.h).
  bool allow_outside_paths = false;
  // Models read through assimp are imported in a child process that may map
  // `import_memory_bytes` more than it inherits and keep ingest waiting
  // `import_seconds` (0 = no limit); a crash or a limit reached there is an
  // InputError naming the file (pipeline/readers/isolated_read.h).
  bool import_in_child_process = true;
  std::uint64_t import_memory_bytes = default_import_memory_bytes();
  double import_seconds = 3600;
  // The up axis to record in the store: "z" or "y"; "" = what the files say
  // (ModelInfo::up), else what the geometry says when it is sure
  // (stages/model_analysis/up_axis_from_geometry.h), else none.
  std::string up;
  // Simplified levels of every chunk for the far field's LOD tier (issue #35;
  // stages/chunk_lod.h), stored in the store's chunk_lods table.
  bool chunk_lods = true;
  ChunkLodParams lod;
};

struct IngestReport {
  std::uint64_t triangles_read = 0;
  std::uint64_t triangles_stored = 0;
  std::uint64_t skipped_degenerate = 0;
  std::uint64_t skipped_duplicate = 0;
  std::uint64_t polygons_triangulated = 0;
  std::uint64_t chunks = 0;
  std::uint64_t chunk_lods = 0;     // simplified chunk levels stored
  std::uint64_t lod_triangles = 0;  // their triangles, all levels together
  std::uint64_t vertices = 0;
  Box3d bounds;
  double read_seconds = 0, chunk_seconds = 0, write_seconds = 0;
  std::string content_hash;  // the store's: GeometryStoreWriter::content_hash(), over what it holds
  // One line per model file with vertex colours: "FILE: vertex colours: ..."
  // (describe_vertex_colours in pipeline/readers/model_reader.h).
  std::vector<std::string> vertex_colour_notes;
  // Textures stored (each distinct image once) and the RGBA8 bytes they decode to.
  std::uint64_t textures = 0;
  std::uint64_t texture_bytes = 0;
  // One line per texture that could not be used, naming the material and the
  // path or reference: "FILE: material 'M': texture 'T' ...: material colour used".
  std::vector<std::string> texture_warnings;
  // What the readers skipped, one line each: "FILE:line N: mtllib 'a.mtl': missing or unreadable; ...".
  std::vector<std::string> input_warnings;
  // The up axis recorded in the store ("z", "y", "" = not recorded) and why:
  // "--up", or "FILE: reason" (e.g. "a.glb: glTF is Y-up by specification",
  // "; the geometry agrees" appended when it does), or "detected from the
  // geometry: EVIDENCE" when no file says (or they disagree), or why none was
  // recorded (no file says and the geometry is not conclusive).
  std::string up, up_source;
  // What the geometry says, over every stored triangle.
  UpAxisGuess up_from_geometry;
  // Non-empty when --up or the files' axis disagrees with a sure answer from
  // the geometry: "warning: ..." naming both (the given or file axis is kept).
  std::string up_warning;
};

// Ingests `models` into a new store at `store` (replacing an existing one only
// on success; on any error the old store is untouched and no temp file stays).
// Throws InputError for bad input (naming file and location) and
// std::runtime_error for I/O failures. An empty model set is an error.
// Deterministic: the same files and params give the same chunks.
IngestReport ingest_models(const std::vector<std::filesystem::path>& models, const std::filesystem::path& store,
                           const IngestParams& params, const ParallelFor& parallel_for,
                           const ProgressCallback& progress = {});

}  // namespace cellbake
