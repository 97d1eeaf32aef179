// Writes a generated scene as a binary little-endian PLY (float x y z, uchar
// RGBA, uint triangle lists), streaming: vertices go straight to the output,
// faces through a temporary file; the result appears atomically (tmp + rename).
#pragma once

#include <filesystem>

#include "stages/scene_generator.h"

namespace cellbake {

// Generates the scene described by `params` into `out`. Returns the summary;
// throws std::runtime_error naming the file on I/O failure.
SceneSummary generate_scene_to_ply(const SceneParams& params, const std::filesystem::path& out);

}  // namespace cellbake
