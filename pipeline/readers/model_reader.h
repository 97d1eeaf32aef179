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
#include <unordered_map>
#include <vector>

#include "stages/geometry.h"
#include "stages/texture.h"

namespace cellbake {

// What a reader did with per-vertex colours (see read_model).
enum class VertexColourUse {
  none,             // the model has no vertex colours
  varying,          // they vary across the file: multiplied into the material colours
  uniform_ignored,  // all equal: material colours used instead (default-material faces keep them)
  uniform_kept,     // all equal, but no face had a material colour to use instead: they are the colour
};

// A texture a material refers to, as the reader found it: a file (path
// resolved against the model's folder) or an image the model file embeds
// (GLB buffers, assimp's "*N" references): encoded bytes with a format hint,
// or raw texels (top row first, as assimp holds them).
struct TextureInput {
  std::filesystem::path file;           // external file; empty when embedded
  std::vector<std::uint8_t> encoded;    // embedded, compressed (PNG, JPEG, ...)
  std::string format_hint;              // embedded: "png", "jpg", ... (may be empty)
  std::vector<Rgba8> texels;            // embedded, uncompressed
  int width = 0, height = 0;            // of `texels`
  TextureWrap wrap_u = TextureWrap::repeat, wrap_v = TextureWrap::repeat;
  bool alpha_allowed = true;            // false when the file says the material is opaque
};

struct ModelInfo {
  std::vector<Material> materials;  // index 0 is always the default material
  // Textures by material index, for materials whose `texture` names one; an
  // external file is already resolved against the folder of the file that
  // names it (the MTL library, the glTF), as a path usable from the working
  // directory. Materials with a texture but no entry here refer to the file
  // Material::texture (absolute or relative to the model's folder).
  std::unordered_map<std::uint32_t, TextureInput> textures;
  VertexColourUse vertex_colours = VertexColourUse::none;
  Rgba8 uniform_vertex_colour{};    // the one colour, when vertex_colours is uniform_*
  std::uint64_t triangles_emitted = 0;
  std::uint64_t polygons_triangulated = 0;  // faces with > 3 corners split into fans
  std::string format;                       // "obj", "ply", "off", "stl", "assimp:<ext>"
  // The model's up axis as the format or file says: "y", "z", or "" when it
  // does not say (OBJ, PLY, OFF, STL), and why, e.g. "glTF is Y-up by specification".
  std::string up, up_source;
  // What the reader skipped, one line each ("line 3: mtllib 'a.mtl': ..."), for the ingest summary.
  std::vector<std::string> warnings;
};

using TriangleCallback = std::function<void(const Triangle&)>;

struct ReadOptions {
  // Files the model names (mtllib, glTF buffers, ...) are read only inside its
  // folder and subfolders unless this is set (pipeline/readers/contained_paths.h).
  bool allow_outside_paths = false;
  // Formats read through assimp are imported in a child process with these
  // limits (pipeline/readers/isolated_read.h): a crash, a runaway allocation
  // or an endless import inside assimp becomes an InputError naming the file.
  // `cellbake ingest` sets it (IngestParams); off, assimp runs in this process.
  bool import_in_child_process = false;
  std::uint64_t import_memory_bytes = 0;  // beyond what the child inherits; 0 = no limit
  double import_seconds = 0;              // 0 = no limit
};

// Reads `file` and calls `emit` for every triangle, in file order. Material
// colours are already multiplied into the per-corner colours; a vertex without
// a colour gets the material colour (default light grey). Vertex colours
// multiply material colours only when they vary across the file; when every
// vertex colour is the same (exporters write "v x y z 0 0 0" or "1 1 1" by
// default) the material colour wins, so such a file is not blanked. Faces
// under the default material (no usemtl / no material) keep their vertex
// colours either way, and formats without materials (PLY, OFF) always use
// them. ModelInfo::vertex_colours says which happened.
// Throws InputError (naming file, line or byte offset, and the problem) for:
// unknown/unsupported format, unreadable/truncated/malformed file, NaN or Inf
// coordinates, out-of-range vertex indices, and (assimp formats) a model that
// cannot load without a file `options` refuses to read, and (assimp formats
// with `options.import_in_child_process`) an import that crashes or exceeds
// the memory or time limit. Other refused references
// are ModelInfo::warnings. Material textures are not opened here: their paths
// are checked where they are read (ingest). Degenerate triangles are emitted
// as they are (ingest counts and skips them). An empty model is not an error here.
ModelInfo read_model(const std::filesystem::path& file, const TriangleCallback& emit,
                     const ReadOptions& options = {});

// One line for the ingest summary about `info`'s vertex colours, e.g.
// "vertex colours: ignored (all equal: 0 0 0), material colours used";
// "" when the model has none.
std::string describe_vertex_colours(const ModelInfo& info);

}  // namespace cellbake
