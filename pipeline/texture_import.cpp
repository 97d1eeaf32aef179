#include "pipeline/texture_import.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <stdexcept>

#include "pipeline/texture_row_reducer.h"
#include "stages/texture_sampling.h"

namespace cellbake {
namespace {

constexpr int kMaxSide = 65536;

// Rows decoded per read (a strip): with the reducer's one row per level and
// the reduced output, the whole of a texture import's memory.
constexpr int kStripRows = 64;

// Halvings (stages/texture_sampling.h halve_texels) until both sides fit `max_size`.
int halvings_to_fit(int width, int height, int max_size) {
  int levels = 0;
  for (; width > max_size || height > max_size; ++levels)
    width = std::max(1, width / 2), height = std::max(1, height / 2);
  return levels;
}

// One row of an OIIO image of `channels` (1 to 4) UINT8 channels as RGBA8.
void row_to_rgba(const std::uint8_t* row, int width, int channels, Rgba8* out) {
  for (int x = 0; x < width; ++x) {
    const std::uint8_t* p = row + std::size_t(x) * std::size_t(channels);
    if (channels <= 2) {
      out[x] = {p[0], p[0], p[0], channels == 2 ? p[1] : std::uint8_t{255}};
    } else {
      out[x] = {p[0], p[1], p[2], channels >= 4 ? p[3] : std::uint8_t{255}};
    }
  }
}

// Reads an image through OpenImageIO: from `path`, or from `proxy` when given
// (then `path` only carries the extension OIIO picks the reader by). The size
// comes from the header (ImageInput::open reads no pixels) and is checked
// first; the pixels are then decoded in strips of kStripRows rows (or of a
// tiled file's tile rows) and halved as they arrive, so memory is bounded by
// the reduced image plus a strip, whatever the file's size.
TextureImage read_with_oiio(const std::string& path, OIIO::Filesystem::IOProxy* proxy,
                            const std::string& name, int max_size) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  if (proxy) config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) throw std::runtime_error("texture " + name + ": " + OIIO::geterror());
  const OIIO::ImageSpec spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.width > kMaxSide || spec.height > kMaxSide ||
      spec.depth > 1)
    throw std::runtime_error("texture " + name + ": unsupported size " + std::to_string(spec.width) + "x" +
                             std::to_string(spec.height));
  const std::uint64_t pixels = std::uint64_t(spec.width) * std::uint64_t(spec.height);
  if (pixels > kMaxTexturePixels)
    throw std::runtime_error("texture " + name + ": " + std::to_string(spec.width) + "x" +
                             std::to_string(spec.height) + " pixels (from its header), more than the " +
                             std::to_string(kMaxTexturePixels) + " a texture may have");
  const int channels = std::clamp(spec.nchannels, 1, 4);
  TextureRowReducer reducer(spec.width, spec.height, halvings_to_fit(spec.width, spec.height, max_size));
  const int strip = spec.tile_width > 0 ? std::max(1, spec.tile_height) : kStripRows;
  const std::size_t row_bytes = std::size_t(spec.width) * std::size_t(channels);
  std::vector<std::uint8_t> raw(row_bytes * std::size_t(strip));
  std::vector<Rgba8> row(std::size_t(spec.width));
  for (int y = 0; y < spec.height; y += strip) {
    const int rows = std::min(strip, spec.height - y);
    const bool ok = spec.tile_width > 0
                        ? in->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + y, spec.y + y + rows,
                                         spec.z, spec.z + 1, 0, channels, OIIO::TypeDesc::UINT8, raw.data())
                        : in->read_scanlines(0, 0, spec.y + y, spec.y + y + rows, spec.z, 0, channels,
                                             OIIO::TypeDesc::UINT8, raw.data());
    if (!ok) throw std::runtime_error("texture " + name + ": " + in->geterror());
    for (int r = 0; r < rows; ++r) {
      row_to_rgba(raw.data() + std::size_t(r) * row_bytes, spec.width, channels, row.data());
      reducer.add_row(row.data());
    }
  }
  TextureImage image;
  image.width = reducer.out_width();
  image.height = reducer.out_height();
  image.texels = reducer.take_bottom_up();
  return image;
}

}  // namespace

void shrink_to_fit(TextureImage& image, int max_size) {
  if (max_size < 1) throw std::invalid_argument("texture size cap must be >= 1");
  while (image.width > max_size || image.height > max_size)
    image.texels = halve_texels(image.texels, image.width, image.height);
}

TextureImage import_texture(const TextureInput& input, const std::string& name,
                            const TextureImportParams& params) {
  if (params.max_size < 1) throw std::invalid_argument("texture size cap must be >= 1");
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
    OIIO::Filesystem::IOMemReader proxy(const_cast<std::uint8_t*>(input.encoded.data()),
                                        input.encoded.size());
    std::string hint = input.format_hint.empty() ? "png" : input.format_hint;
    if (hint == "jpeg") hint = "jpg";
    image = read_with_oiio("embedded." + hint, &proxy, name, params.max_size);
  } else {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(input.file, ec))
      throw std::runtime_error("texture " + name + ": no such file");
    image = read_with_oiio(input.file.string(), nullptr, name, params.max_size);
  }
  shrink_to_fit(image, params.max_size);
  image.wrap_u = input.wrap_u;
  image.wrap_v = input.wrap_v;
  image.has_alpha = input.alpha_allowed && std::any_of(image.texels.begin(), image.texels.end(),
                                                       [](const Rgba8& t) { return t.a < 255; });
  return image;
}

}  // namespace cellbake
