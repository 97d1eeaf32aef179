#include "pipeline/export/gltf_image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <stdexcept>

#include "stages/encode/encode.h"

namespace cellbake {

GltfImage encode_gltf_image(const std::vector<Rgba8>& pixels, int width, int height, bool keep_alpha, int quality) {
  if (width < 1 || height < 1 || pixels.size() != std::size_t(width) * std::size_t(height))
    throw std::invalid_argument("glTF image: " + std::to_string(pixels.size()) + " pixels for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  if (quality < 1 || quality > 100) throw std::invalid_argument("glTF image: quality " + std::to_string(quality) + " is outside 1..100");
  if (keep_alpha) return {encode_image(pixels, width, height, {"png", 100}), "image/png"};
  std::vector<std::uint8_t> rgb(pixels.size() * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    rgb[3 * i] = pixels[i].r;
    rgb[3 * i + 1] = pixels[i].g;
    rgb[3 * i + 2] = pixels[i].b;
  }
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  OIIO::Filesystem::IOProxy* proxy_ptr = &proxy;
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  // The proxy goes in through the spec (as stages/encode/encode.cpp does: OIIO 2.4's
  // JPEG writer crashes when destroyed unopened with a proxy attached).
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
  spec.attribute("Compression", "jpeg:" + std::to_string(quality));
  spec.attribute("jpeg:subsampling", "4:4:4");
  auto output = OIIO::ImageOutput::create("jpg");
  if (!output) throw std::runtime_error("glTF image: no OpenImageIO JPEG writer: " + OIIO::geterror());
  if (!(output->open("memory.jpg", spec) && output->write_image(OIIO::TypeDesc::UINT8, rgb.data()) && output->close()))
    throw std::runtime_error("glTF image: writing JPEG failed: " + output->geterror());
  return {{bytes.begin(), bytes.end()}, "image/jpeg"};
}

}  // namespace cellbake
