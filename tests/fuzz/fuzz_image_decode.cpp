// libFuzzer target: decode_image (stages/encode/encode.h: PNG, JPEG, WebP through
// OpenImageIO, AVIF, JPEG XL) on arbitrary bytes; a decoded image must have
// width x height pixels within the documented caps.
#include <exception>

#include "stages/encode/encode.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cellbake::DecodedImage image;
  try {
    image = cellbake::decode_image(data, size);
  } catch (const std::exception&) {
    return 0;
  }
  if (image.width <= 0 || image.height <= 0 || image.width > 16384 || image.height > 16384 ||
      image.pixels.size() != std::size_t(image.width) * std::size_t(image.height))
    __builtin_trap();
  return 0;
}
