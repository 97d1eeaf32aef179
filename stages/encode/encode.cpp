// Stage `encode`, colour images: JPEG / WebP / PNG through OpenImageIO with
// in-memory I/O proxies (no files); AVIF and JPEG XL through their libraries
// (encode_image_codecs.cpp). Face meshes are in encode_face_mesh.cpp.
#include "stages/encode/encode.h"
#include "stages/encode/encode_image_codecs.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

constexpr int kMaxImageSide = 16384;
constexpr std::int64_t kMaxImagePixels = std::int64_t{1} << 26;

// OpenImageIO's format name for our format name.
std::string oiio_format(const std::string& format) {
  if (format == "jpeg") return "jpg";
  if (format == "webp") return "webp";
  if (format == "png") return "png";
  if (format == "avif") return "avif";
  if (format == "jxl") return "jxl";
  throw std::invalid_argument("encode_image: unknown image format '" + format +
                              "' (expected jpeg, webp, png, avif or jxl)");
}

// Reads and clears OpenImageIO's pending global error text.
std::string take_global_error() { return OIIO::geterror(); }

// The format of an encoded image, from its first bytes, or "" if unknown.
std::string sniff_format(const std::uint8_t* data, std::size_t size) {
  static constexpr std::uint8_t png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size >= 8 && std::memcmp(data, png, 8) == 0) return "png";
  if (size >= 3 && data[0] == 0xff && data[1] == 0xd8 && data[2] == 0xff) return "jpg";
  if (size >= 12 && std::memcmp(data, "RIFF", 4) == 0 && std::memcmp(data + 8, "WEBP", 4) == 0) return "webp";
  if (size >= 12 && std::memcmp(data + 4, "ftypavif", 8) == 0) return "avif";
  static constexpr std::uint8_t jxl_box[12] = {0, 0, 0, 0x0c, 'J', 'X', 'L', ' ', 0x0d, 0x0a, 0x87, 0x0a};
  if ((size >= 2 && data[0] == 0xff && data[1] == 0x0a) || (size >= 12 && std::memcmp(data, jxl_box, 12) == 0))
    return "jxl";
  return "";
}

// Whether an encoded PNG or JPEG ends as every complete file does (PNG: the
// IEND chunk; JPEG: the EOI marker). A cut file may still decode: libjpeg pads
// the missing rows with grey, only warning, and libpng stops before IEND.
bool ends_complete(const std::string& format, const std::uint8_t* data, std::size_t size) {
  if (format == "png") {
    static constexpr std::uint8_t iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
    return size >= 12 && std::memcmp(data + size - 12, iend, 12) == 0;
  }
  if (format == "jpg") return size >= 2 && data[size - 2] == 0xff && data[size - 1] == 0xd9;
  return true;  // WebP, AVIF and JPEG XL carry their lengths: their decoders refuse cut files
}

}  // namespace

std::vector<std::uint8_t> encode_image(const std::vector<Rgba8>& pixels, int width, int height,
                                       const ImageEncodeParams& params) {
  const std::string format = oiio_format(params.format);
  if (width <= 0 || height <= 0 || width > kMaxImageSide || height > kMaxImageSide)
    throw std::invalid_argument("encode_image: bad image size " + std::to_string(width) + "x" +
                                std::to_string(height));
  if (pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw std::invalid_argument("encode_image: " + std::to_string(pixels.size()) + " pixels for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " image");
  if (params.quality < 1 || params.quality > 100)
    throw std::invalid_argument("encode_image: quality " + std::to_string(params.quality) +
                                " is outside 1..100");

  if (format == "avif") return encode_avif(pixels, width, height, params.quality);
  if (format == "jxl") return encode_jxl(pixels, width, height, params.quality);
  const int channels = format == "jpg" ? 3 : 4;
  std::vector<std::uint8_t> raw(pixels.size() * static_cast<std::size_t>(channels));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    std::uint8_t* out = raw.data() + i * static_cast<std::size_t>(channels);
    out[0] = pixels[i].r;
    out[1] = pixels[i].g;
    out[2] = pixels[i].b;
    if (channels == 4) out[3] = pixels[i].a;
  }

  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  OIIO::Filesystem::IOProxy* proxy_ptr = &proxy;
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  // The proxy goes in through the spec, not ImageOutput::create: OIIO 2.4's
  // JPEG writer crashes when destroyed unopened with a proxy already attached.
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
  spec.attribute("Compression", params.format + ":" + std::to_string(params.quality));
  // Our pixels are straight (unassociated) alpha: stop OIIO from converting.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  auto output = OIIO::ImageOutput::create(format);
  if (!output)
    throw std::runtime_error("encode_image: no OpenImageIO writer for " + params.format + ": " +
                             take_global_error());
  const bool ok = output->open("memory." + format, spec) &&
                  output->write_image(OIIO::TypeDesc::UINT8, raw.data()) && output->close();
  if (!ok)
    throw std::runtime_error("encode_image: writing " + params.format + " failed: " + output->geterror());
  return {bytes.begin(), bytes.end()};
}

DecodedImage decode_image(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size == 0) throw std::runtime_error("image blob: empty");
  const std::string format = sniff_format(data, size);
  if (format.empty()) throw std::runtime_error("image blob: not a PNG, JPEG, WebP, AVIF or JPEG XL image");
  if (format == "avif") return decode_avif(data, size, kMaxImageSide, kMaxImagePixels);
  if (format == "jxl") return decode_jxl(data, size, kMaxImageSide, kMaxImagePixels);
  if (!ends_complete(format, data, size))
    throw std::runtime_error("image blob: truncated " + format + " (no " + (format == "png" ? "IEND chunk" : "EOI marker") +
                             " at the end)");

  OIIO::Filesystem::IOMemReader proxy(data, size);
  OIIO::Filesystem::IOProxy* proxy_ptr = &proxy;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
  config.attribute("oiio:UnassociatedAlpha", 1);  // give back straight alpha, as stored
  auto input = OIIO::ImageInput::open("memory." + format, &config);
  if (!input) throw std::runtime_error("image blob: cannot open " + format + ": " + take_global_error());
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.width > kMaxImageSide ||
      spec.height > kMaxImageSide || std::int64_t{spec.width} * spec.height > kMaxImagePixels)
    throw std::runtime_error("image blob: unsupported size " + std::to_string(spec.width) + "x" +
                             std::to_string(spec.height) + "x" + std::to_string(spec.depth));
  const int channels = spec.nchannels;
  if (channels < 1 || channels > 4)
    throw std::runtime_error("image blob: unsupported channel count " + std::to_string(channels));

  DecodedImage image;
  image.width = spec.width;
  image.height = spec.height;
  const std::size_t count = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
  std::vector<std::uint8_t> raw(count * static_cast<std::size_t>(channels));
  if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, raw.data())) {
    const std::string message = input->geterror();
    throw std::runtime_error("image blob: decoding " + format + " failed: " + message);
  }
  // A decoder's warning ("Premature end of JPEG file", "Corrupt JPEG data")
  // means pixels were made up: the image is damaged. OpenImageIO 2.4 keeps the
  // text without has_error() saying so.
  if (std::string warning = input->geterror(); !warning.empty())
    throw std::runtime_error("image blob: damaged " + format + ": " + warning);
  input->close();
  image.pixels.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t* in = raw.data() + i * static_cast<std::size_t>(channels);
    Rgba8& p = image.pixels[i];
    if (channels <= 2) {
      p = {in[0], in[0], in[0], channels == 2 ? in[1] : std::uint8_t{255}};
    } else {
      p = {in[0], in[1], in[2], channels == 4 ? in[3] : std::uint8_t{255}};
    }
  }
  return image;
}

std::string encoded_image_format(const std::vector<std::uint8_t>& bytes) {
  const std::string format = sniff_format(bytes.data(), bytes.size());
  return format == "jpg" ? "jpeg" : format;
}

}  // namespace cellbake
