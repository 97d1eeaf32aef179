// Which texels a bilinearly filtered face mesh reads (stages/texel_footprint.h),
// and filling the others before encoding (stages/background_fill.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stages/background_fill.h"
#include "stages/encode.h"
#include "stages/texel_footprint.h"

namespace cellbake {
namespace {

FaceMesh one_triangle(Uv a, Uv b, Uv c) {
  FaceMesh m;
  m.positions = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.uvs = {a, b, c};
  m.indices = {0, 1, 2};
  return m;
}

// The texels bilinear lookups at a dense grid of points of the triangle read.
std::vector<std::uint8_t> sampled_reads(const FaceMesh& m, int size, int steps) {
  std::vector<std::uint8_t> read(std::size_t(size) * std::size_t(size), 0);
  const Uv a = m.uvs[0], b = m.uvs[1], c = m.uvs[2];
  for (int i = 0; i <= steps; ++i)
    for (int j = 0; i + j <= steps; ++j) {
      const double wb = double(i) / steps, wc = double(j) / steps, wa = 1 - wb - wc;
      const double x = (wa * a.u + wb * b.u + wc * c.u) * size, y = (wa * a.v + wb * b.v + wc * c.v) * size;
      const int x0 = int(std::floor(x - 0.5)), y0 = int(std::floor(y - 0.5));
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int tx = std::clamp(x0 + dx, 0, size - 1), ty = std::clamp(y0 + dy, 0, size - 1);
          // A texel at exactly zero weight is not read.
          const double wx = 1 - std::abs(x - (tx + 0.5)), wy = 1 - std::abs(y - (ty + 0.5));
          if ((wx > 0 && wy > 0) || tx != x0 + dx || ty != y0 + dy) read[std::size_t(ty) * size + tx] = 1;
        }
    }
  return read;
}

TEST(TexelFootprint, EveryTexelABilinearLookupReadsIsMarkedAndLittleElse) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> uv(0.f, 1.f), small(-0.06f, 0.06f);
  const int size = 48;
  for (int round = 0; round < 60; ++round) {
    const Uv a{uv(rng), uv(rng)};
    // Large, small and sliver triangles.
    const float scale = round % 3 == 0 ? 1.f : round % 3 == 1 ? 0.2f : 0.02f;
    const Uv b{std::clamp(a.u + small(rng) * 10 * scale, 0.f, 1.f), std::clamp(a.v + small(rng) * 10 * scale, 0.f, 1.f)};
    const Uv c{std::clamp(a.u + small(rng) * 10 * scale, 0.f, 1.f), std::clamp(a.v + small(rng) * 10 * scale, 0.f, 1.f)};
    const FaceMesh m = one_triangle(a, b, c);
    const std::vector<std::uint8_t> marked = texels_read_by(m, size), sampled = sampled_reads(m, size, 400);
    std::size_t extra = 0, both = 0;
    for (std::size_t k = 0; k < marked.size(); ++k) {
      EXPECT_TRUE(marked[k] || !sampled[k]) << "round " << round << " texel " << k << " read but not marked";
      extra += marked[k] && !sampled[k];
      both += marked[k] && sampled[k];
    }
    // Unmarked-by-sampling texels are those the grid of points just missed at
    // the one-pixel border: a thin rim, not a blanket.
    EXPECT_LE(extra, 4 + both / 3) << "round " << round;
  }
}

TEST(TexelFootprint, NoTrianglesReadNothingAndTwoTrianglesOverTheFaceReadAll) {
  EXPECT_EQ(texels_read_by(FaceMesh{}, 8), std::vector<std::uint8_t>(64, 0));
  FaceMesh quad;
  quad.positions = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  quad.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  quad.indices = {0, 1, 2, 0, 2, 3};
  EXPECT_EQ(texels_read_by(quad, 8), std::vector<std::uint8_t>(64, 1));
  // A triangle in the top-left corner reads a 2 x 2 block of texels... and the
  // ones within a pixel of it.
  const auto corner = texels_read_by(one_triangle({0, 0}, {0.25f, 0}, {0, 0.25f}), 8);
  EXPECT_EQ(corner[0], 1);
  EXPECT_EQ(corner[7], 0);
  EXPECT_EQ(corner[63], 0);
  EXPECT_THROW(texels_read_by(FaceMesh{}, 0), std::invalid_argument);
  FaceMesh bad = one_triangle({0, 0}, {1, 0}, {0, 1});
  bad.indices[2] = 7;
  EXPECT_THROW(texels_read_by(bad, 8), std::invalid_argument);
}

TEST(TexelFootprint, UnreadPixelsAreFilledSoTheImageCodesSmallerAndReadOnesKeepTheirColours) {
  // A covered 64 x 64 face of noise whose mesh textures only its left half.
  const int n = 64;
  CubeFace face;
  face.size = n;
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int k = 0; k < n * n; ++k) {
    face.color.push_back({std::uint8_t(byte(rng)), std::uint8_t(byte(rng)), std::uint8_t(byte(rng)), 255});
    face.depth.push_back(k % n < 60 ? 5.f : kBackgroundDepth);  // a background strip at the right
  }
  FaceMesh left;
  left.positions = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  left.uvs = {{0, 0}, {0.5f, 0}, {0.5f, 1}, {0, 1}};
  left.indices = {0, 1, 2, 0, 2, 3};
  CubeFace background = face, unread = face;
  fill_background_colors(background);
  fill_unread_colors(unread, left);
  const std::vector<std::uint8_t> read = texels_read_by(left, n);
  for (int k = 0; k < n * n; ++k) {
    if (read[std::size_t(k)] && std::isfinite(face.depth[std::size_t(k)]))
      EXPECT_EQ(unread.color[std::size_t(k)], face.color[std::size_t(k)]) << k;
    else
      EXPECT_EQ(unread.color[std::size_t(k)].a, 0) << k;  // filled
    if (!std::isfinite(face.depth[std::size_t(k)])) EXPECT_EQ(background.color[std::size_t(k)].a, 0);
  }
  EXPECT_EQ(read[std::size_t(n / 2 + 1)], 0);  // the right half is not read
  const ImageEncodeParams avif{"avif", 55};
  EXPECT_LT(encode_image(unread.color, n, n, avif).size() * 3, encode_image(background.color, n, n, avif).size() * 2);
}

}  // namespace
}  // namespace cellbake
