// Stage `encode`, AVIF and JPEG XL colour images (see encode_image_codecs.h).
// AV1 still images: AOMedia, "AV1 Image File Format (AVIF)" 1.0 (2019);
// JPEG XL: ISO/IEC 18181-1:2022 (Alakuijala et al.), through libavif and libjxl.
#include "stages/encode/encode_image_codecs.h"

#include <avif/avif.h>
#include <jxl/decode.h>
#include <jxl/encode.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

[[noreturn]] void fail_decode(const std::string& what) { throw std::runtime_error("image blob: " + what); }
[[noreturn]] void fail_encode(const std::string& what) { throw std::runtime_error("encode_image: " + what); }

void check_size(std::uint32_t width, std::uint32_t height, int max_side, std::int64_t max_pixels) {
  if (width == 0 || height == 0 || width > std::uint32_t(max_side) || height > std::uint32_t(max_side) ||
      std::int64_t{width} * height > max_pixels)
    fail_decode("unsupported size " + std::to_string(width) + "x" + std::to_string(height));
}

std::vector<std::uint8_t> rgb_bytes(const std::vector<Rgba8>& pixels) {
  std::vector<std::uint8_t> rgb(pixels.size() * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    rgb[3 * i] = pixels[i].r;
    rgb[3 * i + 1] = pixels[i].g;
    rgb[3 * i + 2] = pixels[i].b;
  }
  return rgb;
}

struct AvifImageFree {
  void operator()(avifImage* p) const { avifImageDestroy(p); }
};
struct AvifEncoderFree {
  void operator()(avifEncoder* p) const { avifEncoderDestroy(p); }
};
struct AvifDecoderFree {
  void operator()(avifDecoder* p) const { avifDecoderDestroy(p); }
};
struct JxlEncoderFree {
  void operator()(JxlEncoder* p) const { JxlEncoderDestroy(p); }
};
struct JxlDecoderFree {
  void operator()(JxlDecoder* p) const { JxlDecoderDestroy(p); }
};

}  // namespace

std::vector<std::uint8_t> encode_avif(const std::vector<Rgba8>& pixels, int width, int height, int quality) {
  std::unique_ptr<avifImage, AvifImageFree> image(
      avifImageCreate(std::uint32_t(width), std::uint32_t(height), 8, AVIF_PIXEL_FORMAT_YUV444));
  if (!image) fail_encode("avifImageCreate failed");
  avifRGBImage rgb;
  avifRGBImageSetDefaults(&rgb, image.get());
  rgb.format = AVIF_RGB_FORMAT_RGBA;
  rgb.depth = 8;
  rgb.pixels = const_cast<std::uint8_t*>(reinterpret_cast<const std::uint8_t*>(pixels.data()));
  rgb.rowBytes = std::uint32_t(width) * 4;
  rgb.ignoreAlpha = AVIF_TRUE;
  if (avifImageRGBToYUV(image.get(), &rgb) != AVIF_RESULT_OK) fail_encode("AVIF colour conversion failed");
  std::unique_ptr<avifEncoder, AvifEncoderFree> encoder(avifEncoderCreate());
  if (!encoder) fail_encode("avifEncoderCreate failed");
  const int q = std::clamp(int(std::lround((100 - quality) * 63.0 / 99.0)), 0, 63);
  encoder->minQuantizer = encoder->maxQuantizer = q;
  // Speed 8: 5-8x faster than the default 6 for ~15 % more bytes at equal
  // PSNR on the demo's faces (docs/benchmark-history.md, issue #16).
  encoder->speed = 8;
  encoder->maxThreads = 1;
  avifRWData out = AVIF_DATA_EMPTY;
  const avifResult r = avifEncoderWrite(encoder.get(), image.get(), &out);
  if (r != AVIF_RESULT_OK) fail_encode(std::string("AVIF: ") + avifResultToString(r));
  std::vector<std::uint8_t> bytes(out.data, out.data + out.size);
  avifRWDataFree(&out);
  return bytes;
}

DecodedImage decode_avif(const std::uint8_t* data, std::size_t size, int max_side, std::int64_t max_pixels) {
  std::unique_ptr<avifDecoder, AvifDecoderFree> decoder(avifDecoderCreate());
  if (!decoder) fail_decode("avifDecoderCreate failed");
  decoder->maxThreads = 1;
  decoder->imageDimensionLimit = std::uint32_t(max_side);
  decoder->imageSizeLimit = std::uint32_t(max_pixels);
  decoder->ignoreExif = decoder->ignoreXMP = AVIF_TRUE;
  std::unique_ptr<avifImage, AvifImageFree> image(avifImageCreateEmpty());
  const avifResult r = avifDecoderReadMemory(decoder.get(), image.get(), data, size);
  if (r != AVIF_RESULT_OK) fail_decode(std::string("decoding avif failed: ") + avifResultToString(r));
  check_size(image->width, image->height, max_side, max_pixels);
  DecodedImage out;
  out.width = int(image->width);
  out.height = int(image->height);
  out.pixels.resize(std::size_t(out.width) * std::size_t(out.height));
  avifRGBImage rgb;
  avifRGBImageSetDefaults(&rgb, image.get());
  rgb.format = AVIF_RGB_FORMAT_RGBA;
  rgb.depth = 8;
  rgb.pixels = reinterpret_cast<std::uint8_t*>(out.pixels.data());
  rgb.rowBytes = std::uint32_t(out.width) * 4;
  if (avifImageYUVToRGB(image.get(), &rgb) != AVIF_RESULT_OK) fail_decode("avif colour conversion failed");
  for (Rgba8& p : out.pixels) p.a = 255;
  return out;
}

std::vector<std::uint8_t> encode_jxl(const std::vector<Rgba8>& pixels, int width, int height, int quality) {
  std::unique_ptr<JxlEncoder, JxlEncoderFree> enc(JxlEncoderCreate(nullptr));
  if (!enc) fail_encode("JxlEncoderCreate failed");
  JxlBasicInfo info;
  JxlEncoderInitBasicInfo(&info);
  info.xsize = std::uint32_t(width);
  info.ysize = std::uint32_t(height);
  info.bits_per_sample = 8;
  info.num_color_channels = 3;
  info.uses_original_profile = JXL_FALSE;
  if (JxlEncoderSetBasicInfo(enc.get(), &info) != JXL_ENC_SUCCESS) fail_encode("JXL basic info rejected");
  JxlColorEncoding colour;
  JxlColorEncodingSetToSRGB(&colour, JXL_FALSE);
  if (JxlEncoderSetColorEncoding(enc.get(), &colour) != JXL_ENC_SUCCESS) fail_encode("JXL colour encoding rejected");
  JxlEncoderFrameSettings* settings = JxlEncoderFrameSettingsCreate(enc.get(), nullptr);
  const double q = quality;
  const double distance = q >= 30 ? 0.1 + (100 - q) * 0.09 : 6.4 + std::pow(2.5, (30 - q) / 5.0) / 6.25;
  if (JxlEncoderSetFrameDistance(settings, float(std::min(distance, 25.0))) != JXL_ENC_SUCCESS ||
      JxlEncoderFrameSettingsSetOption(settings, JXL_ENC_FRAME_SETTING_EFFORT, 7) != JXL_ENC_SUCCESS)
    fail_encode("JXL frame settings rejected");
  const std::vector<std::uint8_t> rgb = rgb_bytes(pixels);
  const JxlPixelFormat format = {3, JXL_TYPE_UINT8, JXL_NATIVE_ENDIAN, 0};
  if (JxlEncoderAddImageFrame(settings, &format, rgb.data(), rgb.size()) != JXL_ENC_SUCCESS)
    fail_encode("JXL frame rejected");
  JxlEncoderCloseInput(enc.get());
  std::vector<std::uint8_t> out(64 * 1024);
  std::uint8_t* next = out.data();
  std::size_t avail = out.size();
  for (;;) {
    const JxlEncoderStatus s = JxlEncoderProcessOutput(enc.get(), &next, &avail);
    if (s == JXL_ENC_SUCCESS) break;
    if (s != JXL_ENC_NEED_MORE_OUTPUT) fail_encode("JXL encoding failed");
    const std::size_t used = std::size_t(next - out.data());
    out.resize(out.size() * 2);
    next = out.data() + used;
    avail = out.size() - used;
  }
  out.resize(std::size_t(next - out.data()));
  return out;
}

DecodedImage decode_jxl(const std::uint8_t* data, std::size_t size, int max_side, std::int64_t max_pixels) {
  std::unique_ptr<JxlDecoder, JxlDecoderFree> dec(JxlDecoderCreate(nullptr));
  if (!dec) fail_decode("JxlDecoderCreate failed");
  if (JxlDecoderSubscribeEvents(dec.get(), JXL_DEC_BASIC_INFO | JXL_DEC_FULL_IMAGE) != JXL_DEC_SUCCESS ||
      JxlDecoderSetInput(dec.get(), data, size) != JXL_DEC_SUCCESS)
    fail_decode("jxl decoder setup failed");
  JxlDecoderCloseInput(dec.get());
  const JxlPixelFormat format = {4, JXL_TYPE_UINT8, JXL_NATIVE_ENDIAN, 0};
  DecodedImage out;
  bool complete = false;
  for (;;) {
    const JxlDecoderStatus s = JxlDecoderProcessInput(dec.get());
    if (s == JXL_DEC_BASIC_INFO) {
      JxlBasicInfo info;
      if (JxlDecoderGetBasicInfo(dec.get(), &info) != JXL_DEC_SUCCESS) fail_decode("jxl basic info unreadable");
      check_size(info.xsize, info.ysize, max_side, max_pixels);
      out.width = int(info.xsize);
      out.height = int(info.ysize);
      out.pixels.resize(std::size_t(out.width) * std::size_t(out.height));
    } else if (s == JXL_DEC_NEED_IMAGE_OUT_BUFFER) {
      std::size_t needed = 0;
      if (out.pixels.empty() || JxlDecoderImageOutBufferSize(dec.get(), &format, &needed) != JXL_DEC_SUCCESS ||
          needed != out.pixels.size() * 4 ||
          JxlDecoderSetImageOutBuffer(dec.get(), &format, out.pixels.data(), needed) != JXL_DEC_SUCCESS)
        fail_decode("jxl output buffer rejected");
    } else if (s == JXL_DEC_FULL_IMAGE) {
      complete = true;  // one frame is all we store
    } else if (s == JXL_DEC_SUCCESS) {
      break;
    } else {
      fail_decode("decoding jxl failed");
    }
  }
  if (!complete) fail_decode("jxl without an image");
  for (Rgba8& p : out.pixels) p.a = 255;
  return out;
}

}  // namespace cellbake
