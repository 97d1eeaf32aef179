#include "viewer/png_file.h"

#include <OpenImageIO/imageio.h>

#include <stdexcept>
#include <string>

namespace cellbake {

void write_png(const std::filesystem::path& file, int width, int height, const std::vector<Rgba8>& pixels,
               bool keep_alpha) {
  if (width < 1 || height < 1 || pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw std::invalid_argument("write_png: image is empty or not width * height pixels");
  const int channels = keep_alpha ? 4 : 3;
  std::vector<unsigned char> data(pixels.size() * static_cast<std::size_t>(channels));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    unsigned char* d = data.data() + i * static_cast<std::size_t>(channels);
    d[0] = pixels[i].r, d[1] = pixels[i].g, d[2] = pixels[i].b;
    if (keep_alpha) d[3] = pixels[i].a;
  }
  auto out = OIIO::ImageOutput::create("png");
  if (!out) throw std::runtime_error("write_png: OpenImageIO has no PNG writer");
  const OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  if (!out->open(file.string(), spec))
    throw std::runtime_error("write_png: cannot open " + file.string() + ": " + out->geterror());
  const bool ok = out->write_image(OIIO::TypeDesc::UINT8, data.data());
  const std::string error = ok ? std::string() : out->geterror();
  if (!out->close() || !ok) throw std::runtime_error("write_png: cannot write " + file.string() + ": " + error);
}

}  // namespace cellbake
