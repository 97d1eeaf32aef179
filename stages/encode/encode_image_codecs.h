// Stage `encode`, colour images that OpenImageIO 2.4 cannot write: AVIF
// (libavif: AV1 still images, aom encoder, dav1d decoder) and JPEG XL
// (libjxl 0.7). Internal to encode.cpp; encode_image / decode_image dispatch
// here. Both code RGB only (alpha is dropped; decode gives 255), 8 bits, and
// decode on the calling thread alone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "stages/encode/encode.h"

namespace cellbake {

// AVIF at `quality` 1..100 (mapped linearly onto AV1 quantizer 63..0), YUV
// 4:4:4 (4:2:0 loses ~5 dB on the baked faces' saturated lit edges), encoder
// speed 8. Throws std::runtime_error("encode_image: ...") when
// libavif fails.
std::vector<std::uint8_t> encode_avif(const std::vector<Rgba8>& pixels, int width, int height, int quality);
// Throws std::runtime_error("image blob: ...") on anything it cannot decode,
// or images larger than `max_side` / `max_pixels`.
DecodedImage decode_avif(const std::uint8_t* data, std::size_t size, int max_side, std::int64_t max_pixels);

// JPEG XL at `quality` 1..100 (cjxl's mapping onto Butteraugli distance:
// 0.1 + (100 - q) * 0.09 from quality 30 up), effort 7, bare codestream.
std::vector<std::uint8_t> encode_jxl(const std::vector<Rgba8>& pixels, int width, int height, int quality);
DecodedImage decode_jxl(const std::uint8_t* data, std::size_t size, int max_side, std::int64_t max_pixels);

}  // namespace cellbake
