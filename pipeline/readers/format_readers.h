// One reader per model format, called by read_model() after it has picked the
// format from the file extension. Each has read_model()'s contract: it calls
// `emit` for every triangle in file order, returns the material table and
// counts, and throws InputError naming the file and the line or byte offset.
#pragma once

#include <filesystem>
#include <string>

#include "pipeline/readers/model_reader.h"

namespace cellbake {

// Wavefront OBJ with its MTL libraries (plain or .gz). Streams faces; holds
// the vertex, texcoord tables and materials. Libraries outside the OBJ's folder
// are skipped with a warning unless `options` allows them.
ModelInfo read_obj(const std::filesystem::path& file, const TriangleCallback& emit, const ReadOptions& options);

// Stanford PLY, ASCII or binary of either byte order (plain or .gz). Holds the
// vertex table; streams faces (a file whose faces precede its vertices is read
// twice rather than buffered).
ModelInfo read_ply(const std::filesystem::path& file, const TriangleCallback& emit);

// Geomview OFF with optional ST/C/N prefixes (plain or .gz). Holds the vertex
// table; streams faces.
ModelInfo read_off(const std::filesystem::path& file, const TriangleCallback& emit);

// STL, ASCII or binary (plain or .gz); fully streamed.
ModelInfo read_stl(const std::filesystem::path& file, const TriangleCallback& emit);

// Any other format assimp can import, loaded whole. `extension` is the
// lower-case format extension without the dot ("gltf", "glb", "3ds", ...).
// A ".gz" file is decompressed into memory and handed to assimp with
// `extension` as the format hint. Every file assimp opens goes through an
// IOSystem that refuses those outside the model's folder unless `options`
// allows them.
ModelInfo read_with_assimp(const std::filesystem::path& file, const std::string& extension, bool gzipped,
                           const TriangleCallback& emit, const ReadOptions& options);

// True when assimp has an importer for `extension` (lower case, no dot).
bool assimp_supports(const std::string& extension);

// The default material every table starts with: light grey, no texture.
inline Material default_material() { return Material{"default", Rgba8{}, ""}; }

}  // namespace cellbake
