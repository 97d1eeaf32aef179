// PNG output of rendered frames through OpenImageIO.
#pragma once

#include <filesystem>
#include <vector>

#include "stages/geometry.h"
#include "storage/output_file.h"

namespace cellbake {

// Writes a row-major RGBA8 image (row 0 at the top) as a PNG file, with alpha
// when `keep_alpha`, else RGB: encoded in memory, then written through an
// OutputFile (never over a database or one of `inputs`; complete or not at
// all). Throws std::invalid_argument for a mis-sized image and
// std::runtime_error naming the file when it cannot be encoded or written.
void write_png(const std::filesystem::path& file, int width, int height, const std::vector<Rgba8>& pixels,
               const InputFiles& inputs, bool keep_alpha = false);

}  // namespace cellbake
