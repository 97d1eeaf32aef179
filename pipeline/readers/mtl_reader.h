// Wavefront MTL material libraries, as referenced by OBJ "mtllib" lines.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

// Appends every "newmtl" of `mtl_file` to `materials` (colour from Kd, alpha
// from d or 1 - Tr, texture from map_Kd resolved against the library's folder;
// a material without Kd is white) and maps its name to its index in
// `by_name` (a later definition of a name wins). Returns false, changing
// nothing, when the file cannot be opened: OBJ readers then fall back to the
// default colour. Throws InputError (file and line) for malformed numbers.
bool read_mtl(const std::filesystem::path& mtl_file, std::vector<Material>& materials,
              std::unordered_map<std::string, std::uint32_t>& by_name);

}  // namespace cellbake
