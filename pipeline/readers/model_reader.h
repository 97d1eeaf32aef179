// Model file readers: stream every triangle of a model file to a callback.
// Formats: OBJ (+ .mtl colours), PLY (ascii / binary little+big endian, vertex
// colours), OFF, STL (ascii / binary), glTF 2.0 / GLB and anything else assimp
// reads; ".gz" variants of OBJ/PLY/OFF/STL are decompressed on the fly.
// OBJ and PLY are streamed (bounded memory apart from the vertex table);
// other formats go through assimp, which loads the whole file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct ModelInfo {
  std::vector<Material> materials;  // index 0 is always the default material
  std::uint64_t triangles_emitted = 0;
  std::uint64_t polygons_triangulated = 0;  // faces with > 3 corners split into fans
  std::string format;                       // "obj", "ply", "off", "stl", "assimp:<ext>"
};

using TriangleCallback = std::function<void(const Triangle&)>;

// Reads `file` and calls `emit` for every triangle, in file order. Material
// colours are already multiplied into the per-corner colours; a vertex without
// a colour gets the material colour (default light grey).
// Throws InputError (naming file, line or byte offset, and the problem) for:
// unknown/unsupported format, unreadable/truncated/malformed file, NaN or Inf
// coordinates, out-of-range vertex indices. Degenerate triangles are emitted
// as they are (ingest counts and skips them). An empty model is not an error here.
ModelInfo read_model(const std::filesystem::path& file, const TriangleCallback& emit);

}  // namespace cellbake
