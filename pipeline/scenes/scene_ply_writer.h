// Writes a procedural scene (pipeline/scenes/scene_generator.h) straight to a binary
// little-endian PLY file, streaming: vertices go to the output as parts
// arrive, faces to a temporary file next to it that is appended at the end.
#pragma once

#include <filesystem>

#include "pipeline/scenes/scene_generator.h"

namespace cellbake {

// Generates the scene for `params` into `out` as binary_little_endian PLY 1.0:
//   element vertex N: float x y z (metres), uchar red green blue alpha
//   element face M:   list uchar uint vertex_indices (always 3)
// The header's counts are padded to a fixed width (trailing spaces) and filled
// in at the end. Writes `out` + ".tmp" (and a faces scratch file beside it)
// and renames onto `out` only on success; on failure nothing is left behind
// and the exception names the file. Never writes over an SQLite database, a
// directory, device, pipe or symbolic link (check_output_target). Same params -> identical bytes. Returns
// the scene summary (triangles == M, vertices == N).
SceneSummary generate_scene_to_ply(const SceneParams& params, const std::filesystem::path& out);

}  // namespace cellbake
