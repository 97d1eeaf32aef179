// Images for a glTF file, which base glTF 2.0 allows only as PNG or JPEG:
// face images stored as AVIF, WebP or JPEG XL and the store's material
// textures are re-encoded through OpenImageIO. JPEG without chroma
// subsampling (4:4:4): cube faces carry colour detail at the pixel scale, and
// 4:2:0 cost 9 dB against `cellbake render` on a 64-pixel face bake (where
// the AVIF faces, 4:4:4 too, lose none).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct GltfImage {
  std::vector<std::uint8_t> bytes;
  std::string mime_type;  // "image/jpeg" | "image/png"
};

// Encodes a row-major RGBA8 image (row 0 at the top): PNG (lossless, with
// alpha) when `keep_alpha`, else JPEG 4:4:4 at `quality` (1..100), alpha
// dropped. Deterministic. Throws std::invalid_argument for a mis-sized image
// or a quality outside 1..100, std::runtime_error("glTF image: ...") when
// OpenImageIO fails.
GltfImage encode_gltf_image(const std::vector<Rgba8>& pixels, int width, int height, bool keep_alpha, int quality);

}  // namespace cellbake
