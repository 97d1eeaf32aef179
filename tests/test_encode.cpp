// Tests for stages/encode: image round trips through OpenImageIO (PNG exact,
// JPEG / WebP within a PSNR bound), face-mesh round trips within the
// documented quantisation error, deterministic bytes, and rejection of
// corrupt blobs (truncations, bit flips, random mutations) without crashing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include "stages/encode.h"

namespace cellbake {
namespace {

std::vector<Rgba8> test_image(int w, int h, bool noisy_alpha) {
  std::vector<Rgba8> px(static_cast<std::size_t>(w) * h);
  std::mt19937 rng(17);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double fx = double(x) / w, fy = double(y) / h;
      Rgba8& p = px[static_cast<std::size_t>(y) * w + x];
      p.r = static_cast<std::uint8_t>(255 * fx);
      p.g = static_cast<std::uint8_t>(255 * fy);
      p.b = static_cast<std::uint8_t>(127 + 120 * std::sin(6 * fx + 4 * fy));
      p.a = noisy_alpha ? static_cast<std::uint8_t>(rng() & 0xff) : 255;
    }
  return px;
}

double psnr_rgb(const std::vector<Rgba8>& a, const std::vector<Rgba8>& b) {
  double se = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double dr = a[i].r - b[i].r, dg = a[i].g - b[i].g, db = a[i].b - b[i].b;
    se += dr * dr + dg * dg + db * db;
  }
  const double mse = se / (3.0 * a.size());
  return mse == 0 ? 1e9 : 10 * std::log10(255.0 * 255.0 / mse);
}

TEST(EncodeImage, PngRoundTripIsExactIncludingAlpha) {
  const auto px = test_image(37, 23, true);
  const auto bytes = encode_image(px, 37, 23, {"png", 85});
  const DecodedImage img = decode_image(bytes);
  EXPECT_EQ(img.width, 37);
  EXPECT_EQ(img.height, 23);
  EXPECT_EQ(img.pixels, px);
}

TEST(EncodeImage, JpegRoundTripWithinPsnrAndOpaque) {
  const auto px = test_image(128, 96, true);
  const auto bytes = encode_image(px, 128, 96, {"jpeg", 90});
  const DecodedImage img = decode_image(bytes);
  ASSERT_EQ(img.width, 128);
  ASSERT_EQ(img.height, 96);
  EXPECT_GT(psnr_rgb(px, img.pixels), 35.0);
  for (const Rgba8& p : img.pixels) ASSERT_EQ(p.a, 255);
  // Lower quality, fewer bytes.
  EXPECT_LT(encode_image(px, 128, 96, {"jpeg", 30}).size(), bytes.size());
}

TEST(EncodeImage, WebpRoundTripWithinPsnr) {
  const auto px = test_image(128, 96, false);
  const auto bytes = encode_image(px, 128, 96, {"webp", 90});
  const DecodedImage img = decode_image(bytes);
  ASSERT_EQ(img.width, 128);
  ASSERT_EQ(img.height, 96);
  EXPECT_GT(psnr_rgb(px, img.pixels), 32.0);
  for (const Rgba8& p : img.pixels) ASSERT_EQ(p.a, 255);
}

TEST(EncodeImage, SameInputGivesSameBytes) {
  const auto px = test_image(64, 64, true);
  for (const char* format : {"jpeg", "webp", "png"}) {
    EXPECT_EQ(encode_image(px, 64, 64, {format, 80}), encode_image(px, 64, 64, {format, 80})) << format;
  }
}

TEST(EncodeImage, RejectsBadArguments) {
  const auto px = test_image(8, 8, false);
  EXPECT_THROW(encode_image(px, 8, 8, {"gif", 80}), std::invalid_argument);
  EXPECT_THROW(encode_image(px, 8, 8, {"jpeg", 0}), std::invalid_argument);
  EXPECT_THROW(encode_image(px, 8, 8, {"jpeg", 101}), std::invalid_argument);
  EXPECT_THROW(encode_image(px, 8, 9, {"png", 80}), std::invalid_argument);
  EXPECT_THROW(encode_image({}, 0, 0, {"png", 80}), std::invalid_argument);
}

// Decoding must either throw std::runtime_error or return a consistent image.
void expect_decode_safe(const std::vector<std::uint8_t>& bytes) {
  try {
    const DecodedImage img = decode_image(bytes);
    EXPECT_GT(img.width, 0);
    EXPECT_EQ(img.pixels.size(), static_cast<std::size_t>(img.width) * img.height);
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("image blob"), std::string::npos) << e.what();
  }
}

TEST(DecodeImage, GarbageThrowsOrDecodesWithoutCrashing) {
  EXPECT_THROW(decode_image(nullptr, 0), std::runtime_error);
  EXPECT_THROW(decode_image(std::vector<std::uint8_t>{1, 2, 3, 4, 5}), std::runtime_error);
  std::mt19937 rng(23);
  const auto px = test_image(32, 32, true);
  for (const char* format : {"jpeg", "webp", "png"}) {
    const auto good = encode_image(px, 32, 32, {format, 80});
    for (std::size_t len :
         {std::size_t{3}, std::size_t{12}, good.size() / 4, good.size() / 2, good.size() - 1})
      expect_decode_safe(
          std::vector<std::uint8_t>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(len)));
    for (int trial = 0; trial < 150; ++trial) {
      auto bad = good;
      const int flips = 1 + static_cast<int>(rng() % 8);
      for (int f = 0; f < flips; ++f)
        bad[12 + rng() % (bad.size() - 12)] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      expect_decode_safe(bad);
    }
    // Valid magic followed by noise.
    auto noise = std::vector<std::uint8_t>(good.begin(), good.begin() + 16);
    for (int i = 0; i < 400; ++i) noise.push_back(static_cast<std::uint8_t>(rng()));
    expect_decode_safe(noise);
  }
}

// ------------------------------------------------------------- face meshes

// A w x h grid of quads over a wavy depth field, uvs in [0, 1].
FaceMesh grid_mesh(int w, int h) {
  FaceMesh m;
  for (int y = 0; y <= h; ++y)
    for (int x = 0; x <= w; ++x) {
      const float s = float(x) / w, t = float(y) / h;
      const float depth = 10.0f + 3.0f * std::sin(5.0f * s) * std::cos(4.0f * t);
      m.positions.push_back({(2 * s - 1) * depth, (1 - 2 * t) * depth, -depth});
      m.uvs.push_back({s, t});
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint32_t a = y * (w + 1) + x, b = a + 1, c = a + (w + 1), d = c + 1;
      m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
    }
  return m;
}

// Triangle rotated so that its smallest index comes first (winding kept).
std::array<std::uint32_t, 3> canonical(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (b < a && b < c) return {b, c, a};
  if (c < a && c < b) return {c, a, b};
  return {a, b, c};
}

// Maps each decoded vertex to the original vertex it came from (nearest
// position), checking the error bounds on the way.
std::vector<std::uint32_t> match_vertices(const FaceMesh& original, const FaceMesh& decoded, double pos_bound,
                                          double uv_bound) {
  std::vector<std::uint32_t> map(decoded.positions.size());
  for (std::size_t i = 0; i < decoded.positions.size(); ++i) {
    const Vec3f& p = decoded.positions[i];
    double best = 1e300;
    for (std::size_t j = 0; j < original.positions.size(); ++j) {
      const Vec3f& q = original.positions[j];
      const double e = std::max({std::fabs(p.x - q.x), std::fabs(p.y - q.y), std::fabs(p.z - q.z)});
      if (e < best) best = e, map[i] = static_cast<std::uint32_t>(j);
    }
    EXPECT_LE(best, pos_bound) << "vertex " << i;
    if (!original.uvs.empty()) {
      const Uv& a = decoded.uvs[i];
      const Uv& b = original.uvs[map[i]];
      EXPECT_LE(std::max(std::fabs(a.u - b.u), std::fabs(a.v - b.v)), uv_bound) << "vertex " << i;
    }
  }
  return map;
}

TEST(FaceMeshCodec, RoundTripKeepsOrderWithinTheErrorBound) {
  const FaceMesh m = grid_mesh(24, 17);
  MeshEncodeParams params;
  params.optimize_order = false;
  const FaceMesh d = decode_face_mesh(encode_face_mesh(m, params));
  ASSERT_EQ(d.positions.size(), m.positions.size());
  ASSERT_EQ(d.uvs.size(), m.uvs.size());
  ASSERT_EQ(d.indices.size(), m.indices.size());
  const double bound = face_mesh_position_error_bound(m, 16);
  EXPECT_LT(bound, 13.0 * 2 / 65535);  // extent ~26 m over 16 bits
  const double uv_bound = face_mesh_uv_error_bound(m);
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    EXPECT_NEAR(d.positions[i].x, m.positions[i].x, bound);
    EXPECT_NEAR(d.positions[i].y, m.positions[i].y, bound);
    EXPECT_NEAR(d.positions[i].z, m.positions[i].z, bound);
    EXPECT_NEAR(d.uvs[i].u, m.uvs[i].u, uv_bound);
    EXPECT_NEAR(d.uvs[i].v, m.uvs[i].v, uv_bound);
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    EXPECT_EQ(canonical(d.indices[3 * t], d.indices[3 * t + 1], d.indices[3 * t + 2]),
              canonical(m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]));
}

TEST(FaceMeshCodec, OptimizedOrderKeepsTheSameTrianglesAndIsSmaller) {
  FaceMesh m = grid_mesh(20, 20);
  // Shuffle triangles so that reordering has something to gain.
  std::mt19937 rng(5);
  std::vector<std::size_t> order(m.triangle_count());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<std::uint32_t> shuffled;
  for (std::size_t t : order)
    shuffled.insert(shuffled.end(), m.indices.begin() + 3 * t, m.indices.begin() + 3 * t + 3);
  m.indices = shuffled;

  MeshEncodeParams keep, optimize;
  keep.optimize_order = false;
  const auto kept_bytes = encode_face_mesh(m, keep);
  const auto optimized_bytes = encode_face_mesh(m, optimize);
  EXPECT_LT(optimized_bytes.size(), kept_bytes.size());

  const FaceMesh d = decode_face_mesh(optimized_bytes);
  const auto map = match_vertices(m, d, face_mesh_position_error_bound(m, 16), face_mesh_uv_error_bound(m));
  std::map<std::array<std::uint32_t, 3>, int> expected, got;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    ++expected[canonical(m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2])];
  for (std::size_t t = 0; t < d.triangle_count(); ++t)
    ++got[canonical(map[d.indices[3 * t]], map[d.indices[3 * t + 1]], map[d.indices[3 * t + 2]])];
  EXPECT_EQ(got, expected);
}

TEST(FaceMeshCodec, ErrorBoundHoldsForEveryBitDepth) {
  const FaceMesh m = grid_mesh(12, 9);
  for (int bits : {1, 4, 8, 12, 16}) {
    MeshEncodeParams params;
    params.position_bits = bits;
    params.optimize_order = false;
    const FaceMesh d = decode_face_mesh(encode_face_mesh(m, params));
    const double bound = face_mesh_position_error_bound(m, bits);
    double worst = 0;
    for (std::size_t i = 0; i < m.positions.size(); ++i)
      worst = std::max({worst, double(std::fabs(d.positions[i].x - m.positions[i].x)),
                        double(std::fabs(d.positions[i].y - m.positions[i].y)),
                        double(std::fabs(d.positions[i].z - m.positions[i].z))});
    EXPECT_LE(worst, bound) << bits << " bits";
    if (bits >= 4) {
      EXPECT_GT(worst, bound * 0.25) << "the bound should be tight at " << bits << " bits";
    }
  }
}

TEST(FaceMeshCodec, EmptyFlatAndUvLessMeshes) {
  EXPECT_TRUE(decode_face_mesh(encode_face_mesh(FaceMesh{}, {})).positions.empty());
  FaceMesh flat;  // all vertices at one point: zero extent on every axis
  flat.positions = {{1, 2, 3}, {1, 2, 3}, {1, 2, 3}};
  flat.indices = {0, 1, 2};
  const FaceMesh d = decode_face_mesh(encode_face_mesh(flat, {}));
  ASSERT_EQ(d.positions.size(), 3u);
  EXPECT_TRUE(d.uvs.empty());
  for (const Vec3f& p : d.positions) EXPECT_EQ(p, (Vec3f{1, 2, 3}));
}

TEST(FaceMeshCodec, SameInputGivesSameBytes) {
  const FaceMesh m = grid_mesh(30, 20);
  EXPECT_EQ(encode_face_mesh(m, {}), encode_face_mesh(m, {}));
}

TEST(FaceMeshCodec, EncodeRejectsBadMeshes) {
  FaceMesh m = grid_mesh(2, 2);
  MeshEncodeParams p;
  p.position_bits = 0;
  EXPECT_THROW(encode_face_mesh(m, p), std::invalid_argument);
  p.position_bits = 17;
  EXPECT_THROW(encode_face_mesh(m, p), std::invalid_argument);
  FaceMesh bad = m;
  bad.indices.push_back(0);
  EXPECT_THROW(encode_face_mesh(bad, {}), std::invalid_argument);
  bad = m;
  bad.indices[4] = 99;
  EXPECT_THROW(encode_face_mesh(bad, {}), std::invalid_argument);
  bad = m;
  bad.positions[1].y = std::nanf("");
  EXPECT_THROW(encode_face_mesh(bad, {}), std::invalid_argument);
  bad = m;
  bad.uvs.pop_back();
  EXPECT_THROW(encode_face_mesh(bad, {}), std::invalid_argument);
}

// A decode must throw "face mesh blob: ..." or give a self-consistent mesh.
void expect_mesh_decode_safe(const std::uint8_t* data, std::size_t size) {
  try {
    const FaceMesh d = decode_face_mesh(data, size);
    ASSERT_EQ(d.indices.size() % 3, 0u);
    ASSERT_TRUE(d.uvs.empty() || d.uvs.size() == d.positions.size());
    for (std::uint32_t i : d.indices) ASSERT_LT(i, d.positions.size());
  } catch (const std::runtime_error& e) {
    ASSERT_EQ(std::string(e.what()).rfind("face mesh blob: ", 0), 0u) << e.what();
  }
}

TEST(FaceMeshCodec, CorruptBlobsAreRejectedWithoutCrashing) {
  const auto good = encode_face_mesh(grid_mesh(6, 5), {});
  // Every truncation.
  for (std::size_t len = 0; len < good.size(); ++len) {
    EXPECT_THROW(decode_face_mesh(good.data(), len), std::runtime_error) << "length " << len;
  }
  // Every single-bit flip.
  for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
    auto bad = good;
    bad[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    expect_mesh_decode_safe(bad.data(), bad.size());
  }
  // Random multi-byte mutations, insertions and deletions.
  std::mt19937 rng(99);
  for (int trial = 0; trial < 20000; ++trial) {
    auto bad = good;
    const int edits = 1 + static_cast<int>(rng() % 6);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % bad.size();
      switch (rng() % 3) {
        case 0:
          bad[at] = static_cast<std::uint8_t>(rng());
          break;
        case 1:
          bad.insert(bad.begin() + static_cast<std::ptrdiff_t>(at), static_cast<std::uint8_t>(rng()));
          break;
        default:
          if (bad.size() > 1) bad.erase(bad.begin() + static_cast<std::ptrdiff_t>(at));
          break;
      }
    }
    expect_mesh_decode_safe(bad.data(), bad.size());
  }
  // Pure noise, and noise behind a valid header.
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<std::uint8_t> noise(rng() % 400);
    for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
    expect_mesh_decode_safe(noise.data(), noise.size());
    std::vector<std::uint8_t> framed(good.begin(), good.begin() + 64);
    framed.insert(framed.end(), noise.begin(), noise.end());
    expect_mesh_decode_safe(framed.data(), framed.size());
  }
}

TEST(FaceMeshCodec, LyingCountsAreRejectedBeforeAllocating) {
  auto blob = encode_face_mesh(grid_mesh(4, 4), {});
  auto lie = blob;
  lie[8] = lie[9] = lie[10] = lie[11] = 0xff;  // vertex_count = 2^32 - 1
  EXPECT_THROW(decode_face_mesh(lie), std::runtime_error);
  lie = blob;
  lie[12] = 0xfc, lie[13] = lie[14] = 0xff, lie[15] = 0x7f;  // a huge multiple of 3... or not
  EXPECT_THROW(decode_face_mesh(lie), std::runtime_error);
  lie = blob;
  lie[0] = 'X';
  EXPECT_THROW(decode_face_mesh(lie), std::runtime_error);
}

}  // namespace
}  // namespace cellbake
