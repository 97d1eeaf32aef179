#include "viewer/png_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <stdexcept>
#include <string>
#include <string_view>

namespace cellbake {

void write_png(const std::filesystem::path& file, int width, int height, const std::vector<Rgba8>& pixels,
               const InputFiles& inputs, bool keep_alpha) {
  if (width < 1 || height < 1 ||
      pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw std::invalid_argument("write_png: image is empty or not width * height pixels");
  OutputFile out(file, inputs);  // refused before anything is encoded
  const int channels = keep_alpha ? 4 : 3;
  std::vector<unsigned char> data(pixels.size() * static_cast<std::size_t>(channels));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    unsigned char* d = data.data() + i * static_cast<std::size_t>(channels);
    d[0] = pixels[i].r, d[1] = pixels[i].g, d[2] = pixels[i].b;
    if (keep_alpha) d[3] = pixels[i].a;
  }
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  OIIO::Filesystem::IOProxy* proxy_ptr = &proxy;
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);  // through the spec: see stages/encode/encode.cpp
  auto png = OIIO::ImageOutput::create("png");
  if (!png) throw std::runtime_error("write_png: OpenImageIO has no PNG writer");
  const bool ok =
      png->open("memory.png", spec) && png->write_image(OIIO::TypeDesc::UINT8, data.data()) && png->close();
  if (!ok || bytes.empty())
    throw std::runtime_error(file.string() + ": cannot encode the PNG: " + png->geterror());
  out.write(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  out.commit();
}

}  // namespace cellbake
