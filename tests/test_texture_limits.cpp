// Texture limits applied from the image header before decoding (issue #37):
// a header claiming 65,500 x 65,500 is refused at once, and a large texture
// is decoded in strips and halved to --max-texture-size as it arrives, with
// the same texels as decoding it whole and halving.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <zlib.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "pipeline/texture_import.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::TempDir;

// Writes a `width` x `height` image of `channels` channels (a pattern that
// differs in every channel and texel) to `file`; tiled when `tile` > 0.
void write_image(const std::filesystem::path& file, int width, int height, int channels, int tile = 0) {
  auto out = OIIO::ImageOutput::create(file.string());
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
  if (tile > 0) spec.tile_width = spec.tile_height = tile;
  std::vector<std::uint8_t> pixels(std::size_t(width) * std::size_t(height) * std::size_t(channels));
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = std::uint8_t((i * 2654435761u) >> 13);
  ASSERT_TRUE(out->open(file.string(), spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, pixels.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

std::vector<unsigned char> read_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void write_bytes(const std::filesystem::path& file, const std::vector<unsigned char>& bytes) {
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// What import_texture made before strips: the whole image decoded, converted
// to RGBA8 bottom row first, then halved by shrink_to_fit.
TextureImage decoded_whole_then_halved(const std::filesystem::path& file, int max_size) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // as import_texture reads
  auto in = OIIO::ImageInput::open(file.string(), &config);
  const OIIO::ImageSpec spec = in->spec();
  const int channels = std::clamp(spec.nchannels, 1, 4);
  std::vector<std::uint8_t> raw(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(channels));
  EXPECT_TRUE(in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, raw.data()));
  TextureImage image;
  image.width = spec.width, image.height = spec.height;
  for (int y = spec.height - 1; y >= 0; --y)
    for (int x = 0; x < spec.width; ++x) {
      const std::uint8_t* p =
          raw.data() + (std::size_t(y) * std::size_t(spec.width) + std::size_t(x)) * channels;
      image.texels.push_back(channels <= 2
                                 ? Rgba8{p[0], p[0], p[0], channels == 2 ? p[1] : std::uint8_t{255}}
                                 : Rgba8{p[0], p[1], p[2], channels == 4 ? p[3] : std::uint8_t{255}});
    }
  shrink_to_fit(image, max_size);
  return image;
}

TEST(TextureLimits, StripDecodingEqualsDecodingWholeThenHalving) {
  TempDir dir;
  struct Case {
    const char* name;
    int width, height, channels, tile, max_size;
  };
  for (const Case& c : {Case{"odd.png", 1001, 767, 3, 0, 100}, Case{"row.png", 257, 1, 2, 0, 16},
                        Case{"column.png", 1, 300, 1, 0, 7}, Case{"fits.png", 300, 301, 4, 0, 301},
                        Case{"tall.png", 64, 1000, 3, 0, 50}, Case{"tiled.tif", 300, 200, 4, 64, 64}}) {
    write_image(dir / c.name, c.width, c.height, c.channels, c.tile);
    if (c.tile)
      EXPECT_EQ(OIIO::ImageInput::open((dir / c.name).string())->spec().tile_width, c.tile);  // read_tiles
    TextureInput input;
    input.file = dir / c.name;
    const TextureImage strips = import_texture(input, c.name, {c.max_size});
    const TextureImage whole = decoded_whole_then_halved(dir / c.name, c.max_size);
    EXPECT_EQ(strips.width, whole.width) << c.name;
    EXPECT_EQ(strips.height, whole.height) << c.name;
    EXPECT_LE(std::max(strips.width, strips.height), c.max_size) << c.name;
    EXPECT_TRUE(strips.texels == whole.texels) << c.name;
  }
}

TEST(TextureLimits, AJpegHeaderClaiming65500SquaredIsRefusedFromItsHeader) {
  TempDir dir;
  write_image(dir / "small.jpg", 16, 16, 3);
  std::vector<unsigned char> jpeg = read_bytes(dir / "small.jpg");
  bool patched = false;
  for (std::size_t i = 2; i + 9 < jpeg.size() && !patched; ++i)
    if (jpeg[i] == 0xFF && (jpeg[i + 1] == 0xC0 || jpeg[i + 1] == 0xC2)) {  // SOF: height, width at +5, +7
      jpeg[i + 5] = jpeg[i + 7] = 65500 >> 8;
      jpeg[i + 6] = jpeg[i + 8] = 65500 & 255;
      patched = true;
    }
  ASSERT_TRUE(patched);
  write_bytes(dir / "huge.jpg", jpeg);
  TextureInput input;
  input.file = dir / "huge.jpg";
  const auto start = std::chrono::steady_clock::now();
  try {
    import_texture(input, "'huge.jpg'", {});
    ADD_FAILURE() << "a 65500 x 65500 header was decoded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "huge.jpg': 65500x65500 pixels (from its header), more than the 1073741824"),
              std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);

  // Through ingest: a warning naming the texture, the material keeps its colour, within seconds.
  test::write_text(dir / "m.mtl", "newmtl m\nKd 1 1 1\nmap_Kd huge.jpg\n");
  test::write_text(dir / "m.obj",
                   "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 3/1\n");
  const test::CommandResult r =
      test::run_cellbake("ingest " + (dir / "m.obj").string() + " --store " + (dir / "s.db").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("65500x65500 pixels (from its header)"), std::string::npos) << r.output;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 12.0);
}

TEST(TextureLimits, APngHeaderClaimingMorePixelsThanTheCapIsRefused) {
  TempDir dir;
  write_image(dir / "small.png", 8, 8, 3);
  std::vector<unsigned char> png = read_bytes(dir / "small.png");
  ASSERT_GE(png.size(), 33u);
  ASSERT_EQ(std::string(png.begin() + 12, png.begin() + 16), "IHDR");
  for (int at : {16, 20}) {  // width, height: 40000 (big endian)
    png[at] = png[at + 1] = 0;
    png[at + 2] = 40000 >> 8;
    png[at + 3] = 40000 & 255;
  }
  const uLong crc = crc32(0, png.data() + 12, 17);  // over "IHDR" and its 13 bytes
  for (int k = 0; k < 4; ++k) png[29 + k] = static_cast<unsigned char>(crc >> (24 - 8 * k));
  write_bytes(dir / "huge.png", png);
  TextureInput input;
  input.file = dir / "huge.png";
  EXPECT_THROW(
      {
        try {
          import_texture(input, "'huge.png'", {});
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("40000x40000 pixels (from its header)"), std::string::npos)
              << e.what();
          throw;
        }
      },
      std::runtime_error);
}

}  // namespace
}  // namespace cellbake
