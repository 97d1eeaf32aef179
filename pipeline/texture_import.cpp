#include "pipeline/texture_import.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <stdexcept>

#include "stages/texture_sampling.h"

namespace cellbake {
namespace {

constexpr int kMaxSide = 65536;

// RGBA8 texels, bottom row first, from an OIIO image of `channels` channels
// stored top row first.
std::vector<Rgba8> to_rgba_bottom_up(const std::vector<std::uint8_t>& raw, int width, int height, int channels) {
  std::vector<Rgba8> out(std::size_t(width) * std::size_t(height));
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* row = raw.data() + std::size_t(height - 1 - y) * std::size_t(width) * std::size_t(channels);
    for (int x = 0; x < width; ++x) {
      const std::uint8_t* p = row + std::size_t(x) * std::size_t(channels);
      Rgba8& t = out[std::size_t(y) * std::size_t(width) + std::size_t(x)];
      if (channels <= 2) {
        t = {p[0], p[0], p[0], channels == 2 ? p[1] : std::uint8_t{255}};
      } else {
        t = {p[0], p[1], p[2], channels >= 4 ? p[3] : std::uint8_t{255}};
      }
    }
  }
  return out;
}

// Reads an image through OpenImageIO: from `path`, or from `proxy` when given
// (then `path` only carries the extension OIIO picks the reader by).
TextureImage read_with_oiio(const std::string& path, OIIO::Filesystem::IOProxy* proxy, const std::string& name) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  if (proxy) config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) throw std::runtime_error("texture " + name + ": " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.width > kMaxSide || spec.height > kMaxSide || spec.depth > 1)
    throw std::runtime_error("texture " + name + ": unsupported size " + std::to_string(spec.width) + "x" +
                             std::to_string(spec.height));
  const int channels = std::clamp(spec.nchannels, 1, 4);
  std::vector<std::uint8_t> raw(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, raw.data()))
    throw std::runtime_error("texture " + name + ": " + in->geterror());
  TextureImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.texels = to_rgba_bottom_up(raw, spec.width, spec.height, channels);
  return image;
}

}  // namespace

void shrink_to_fit(TextureImage& image, int max_size) {
  if (max_size < 1) throw std::invalid_argument("texture size cap must be >= 1");
  while (image.width > max_size || image.height > max_size)
    image.texels = halve_texels(image.texels, image.width, image.height);
}

TextureImage import_texture(const TextureInput& input, const std::string& name, const TextureImportParams& params) {
  TextureImage image;
  if (!input.texels.empty()) {
    if (input.width <= 0 || input.height <= 0 ||
        input.texels.size() != std::size_t(input.width) * std::size_t(input.height))
      throw std::runtime_error("texture " + name + ": embedded texels do not match their size");
    image.width = input.width;
    image.height = input.height;
    image.texels.resize(input.texels.size());
    for (int y = 0; y < input.height; ++y)  // assimp holds the top row first
      std::copy_n(input.texels.begin() + std::ptrdiff_t(input.height - 1 - y) * input.width, input.width,
                  image.texels.begin() + std::ptrdiff_t(y) * input.width);
  } else if (!input.encoded.empty()) {
    OIIO::Filesystem::IOMemReader proxy(const_cast<std::uint8_t*>(input.encoded.data()), input.encoded.size());
    std::string hint = input.format_hint.empty() ? "png" : input.format_hint;
    if (hint == "jpeg") hint = "jpg";
    image = read_with_oiio("embedded." + hint, &proxy, name);
  } else {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(input.file, ec))
      throw std::runtime_error("texture " + name + ": no such file");
    image = read_with_oiio(input.file.string(), nullptr, name);
  }
  shrink_to_fit(image, params.max_size);
  image.wrap_u = input.wrap_u;
  image.wrap_v = input.wrap_v;
  image.has_alpha = input.alpha_allowed &&
                    std::any_of(image.texels.begin(), image.texels.end(), [](const Rgba8& t) { return t.a < 255; });
  return image;
}

}  // namespace cellbake
