// Texture images as ingest stores them: any format OpenImageIO reads (PNG,
// JPEG, TGA, BMP, TIFF, ...) from a file or from bytes a model embeds, or raw
// texels, converted to RGBA8 bottom row first (stages/texture.h) and
// box-filtered by halving (as mip levels are) until both sides fit the size cap.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "pipeline/readers/model_reader.h"
#include "stages/texture.h"

namespace cellbake {

// Texture files with more pixels than this (32768 x 32768) are refused from
// their header, before decoding (docs/reliability.md).
inline constexpr std::uint64_t kMaxTexturePixels = std::uint64_t{1} << 30;

struct TextureImportParams {
  int max_size = 2048;  // longest side after import (>= 1); larger images are halved until they fit
};

// Decodes `input` (TextureInput from a reader: file, embedded bytes or texels)
// into a TextureImage with its wrap modes and has_alpha set. `name` names the
// texture in errors. Throws std::runtime_error naming it when the image is
// missing, unreadable, empty, larger than 65536 pixels a side or than
// kMaxTexturePixels in all. An image file's size is read from its header
// before any pixel is decoded; its pixels are decoded in strips and halved to
// `params.max_size` as they arrive (the same texels as decoding it whole and
// calling shrink_to_fit), so memory is bounded by the result plus a strip.
TextureImage import_texture(const TextureInput& input, const std::string& name,
                            const TextureImportParams& params);

// Halves `image` (halve_texels in stages/texture_sampling.h: the box filter of
// a GL mip level) until width and height are both <= max_size. Exposed for tests.
void shrink_to_fit(TextureImage& image, int max_size);

}  // namespace cellbake
