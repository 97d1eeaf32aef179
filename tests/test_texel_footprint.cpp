// Which texels a bilinearly filtered face mesh reads (stages/texel_footprint.h),
// and filling the others before encoding (stages/background_fill.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stages/background_fill.h"
#include "stages/encode/encode.h"
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

// The per-texel test texels_read_by answers (its contract): the square of
// half-size h around the texel centre against each edge's side, texel by texel.
bool square_overlaps_triangle(const FaceMesh& m, int size, int x, int y, double h) {
  double px[3], py[3];
  for (int c = 0; c < 3; ++c) px[c] = double(m.uvs[c].u) * size, py[c] = double(m.uvs[c].v) * size;
  const double cx = x + 0.5, cy = y + 0.5;
  for (int e = 0; e < 3; ++e) {
    const int a = e, b = (e + 1) % 3, r = (e + 2) % 3;
    const double nx = py[b] - py[a], ny = px[a] - px[b];
    if (nx == 0 && ny == 0) continue;
    const double side = nx * (px[r] - px[a]) + ny * (py[r] - py[a]);
    const double centre = nx * (cx - px[a]) + ny * (cy - py[a]), reach = h * (std::abs(nx) + std::abs(ny));
    if (side >= 0 ? centre + reach < 0 : centre - reach > 0) return false;
  }
  return true;
}

// Row runs (texels_read_by finds each row's run from the edges) mark exactly
// the texels the per-texel test accepts, also where a square only touches an
// edge: lattice-aligned corners (as the bake's meshes have), axis-parallel,
// degenerate and sliver triangles.
TEST(TexelFootprint, RowRunsMarkExactlyTheTexelsWhoseSquareMeetsTheTriangle) {
  std::mt19937 rng(11);
  const int size = 40;
  std::uniform_int_distribution<int> lattice(-2, size + 2);
  std::uniform_real_distribution<float> anywhere(-0.05f, 1.05f);
  std::size_t texels = 0;
  for (int round = 0; round < 3000; ++round) {
    Uv c[3];
    for (Uv& v : c) {
      if (round % 2 == 0) v = {float(lattice(rng)) / size, float(lattice(rng)) / size};
      else v = {anywhere(rng), anywhere(rng)};
    }
    if (round % 7 == 1) c[2] = c[1];                                                // a repeated corner
    if (round % 7 == 2) c[1].v = c[0].v;                                            // a horizontal edge
    if (round % 7 == 3) c[2].u = c[0].u;                                            // a vertical edge
    if (round % 7 == 4) c[2] = {(c[0].u + c[1].u) / 2, (c[0].v + c[1].v) / 2};      // collinear
    if (round % 7 == 5) c[2] = {c[1].u + 0.3f / size, c[1].v + 0.001f / size};     // a sliver
    const FaceMesh m = one_triangle(c[0], c[1], c[2]);
    const std::vector<std::uint8_t> marked = texels_read_by(m, size);
    const double h = 1.0 + 1e-6;
    double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
    for (const Uv& v : c) {
      lo_x = std::min(lo_x, double(v.u) * size), hi_x = std::max(hi_x, double(v.u) * size);
      lo_y = std::min(lo_y, double(v.v) * size), hi_y = std::max(hi_y, double(v.v) * size);
    }
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const bool in_box = x + 0.5 >= lo_x - h && x + 0.5 <= hi_x + h && y + 0.5 >= lo_y - h && y + 0.5 <= hi_y + h;
        const bool expected = in_box && square_overlaps_triangle(m, size, x, y, h);
        texels += expected;
        ASSERT_EQ(marked[std::size_t(y) * size + x] != 0, expected) << "round " << round << " texel " << x << "," << y;
      }
  }
  EXPECT_GT(texels, 100000u);  // the triangles do cover texels
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
