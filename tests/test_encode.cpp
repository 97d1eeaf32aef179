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

#include "stages/depth_mesh.h"
#include "stages/encode/encode.h"
#include "stages/simplify/simplify.h"

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

TEST(EncodeImage, AvifAndJxlRoundTripWithinPsnrAndOpaque) {
  const auto px = test_image(128, 96, true);
  for (const char* format : {"avif", "jxl"}) {
    const auto bytes = encode_image(px, 128, 96, {format, 90});
    const DecodedImage img = decode_image(bytes);
    ASSERT_EQ(img.width, 128) << format;
    ASSERT_EQ(img.height, 96) << format;
    EXPECT_GT(psnr_rgb(px, img.pixels), 35.0) << format;
    for (const Rgba8& p : img.pixels) ASSERT_EQ(p.a, 255);
    EXPECT_LT(encode_image(px, 128, 96, {format, 30}).size(), bytes.size()) << format;
  }
}

TEST(EncodeImage, SameInputGivesSameBytes) {
  const auto px = test_image(64, 64, true);
  for (const char* format : {"jpeg", "webp", "png", "avif", "jxl"}) {
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
  for (const char* format : {"jpeg", "webp", "png", "avif", "jxl"}) {
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

// A cut image is an error in every format, however little is missing (libjpeg
// pads a cut JPEG with grey and only warns; libpng never reads the IEND chunk).
TEST(DecodeImage, CutImagesAreErrorsInEveryFormat) {
  const auto px = test_image(64, 48, false);
  for (const char* format : {"jpeg", "webp", "png", "avif", "jxl"}) {
    const auto good = encode_image(px, 64, 48, {format, 85});
    ASSERT_NO_THROW(decode_image(good)) << format;
    for (std::size_t len : {good.size() / 2, good.size() * 9 / 10, good.size() - 2, good.size() - 1}) {
      const std::vector<std::uint8_t> cut(good.begin(), good.begin() + std::ptrdiff_t(len));
      EXPECT_THROW(decode_image(cut), std::runtime_error) << format << " cut to " << len << " of " << good.size();
    }
  }
  const auto jpeg = encode_image(test_image(256, 192, false), 256, 192, {"jpeg", 85});  // mostly entropy-coded data
  try {
    decode_image(std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + std::ptrdiff_t(jpeg.size() / 2)));
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "image blob: truncated jpg (no EOI marker at the end)");
  }
  // The end marker alone does not make a cut JPEG whole: libjpeg's warning is an error too.
  std::vector<std::uint8_t> patched(jpeg.begin(), jpeg.begin() + std::ptrdiff_t(jpeg.size() * 3 / 4));
  patched.insert(patched.end(), {0xff, 0xd9});
  try {
    decode_image(patched);
    ADD_FAILURE() << "a JPEG cut to 3/4 decoded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("image blob: damaged jpg: "), std::string::npos) << e.what();
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

// ------------------------------------------------- grid face meshes (v2)

namespace cellbake {
namespace {

// An n x n pixel-corner grid on cube face `face`, every vertex on its corner
// ray at a wavy planar depth (as build_depth_meshes places them), two
// triangles per pixel.
FaceMesh ray_grid_mesh(int face, int n, double near_depth = 3.0) {
  const FaceBasis b = cube_face_basis(face);
  FaceMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double z = near_depth * (1.0 + 0.4 * std::sin(0.3 * i) * std::cos(0.2 * j) + 0.01 * i);
      const Vec3d d = cube_face_direction(b, 2.0 * i / n - 1, 1 - 2.0 * j / n) * z;
      m.positions.push_back({float(d.x), float(d.y), float(d.z)});
      m.uvs.push_back({float(i) / float(n), float(j) / float(n)});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * (n + 1) + i), c = a + std::uint32_t(n + 1);
      m.indices.insert(m.indices.end(), {a, c, c + 1, a, c + 1, a + 1});
    }
  return m;
}

MeshEncodeParams grid_params(int face, int n, double error = 0.001) {
  MeshEncodeParams p;
  p.face = face;
  p.face_size = n;
  p.depth_error_relative = error;
  return p;
}

// Pixel corner and planar depth of each vertex, sorted (vertex order changes).
std::vector<std::array<double, 3>> corners_and_depths(const FaceMesh& m, int face, int n) {
  const FaceBasis b = cube_face_basis(face);
  std::vector<std::array<double, 3>> out;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const Vec3f& p = m.positions[v];
    out.push_back({double(m.uvs[v].u) * n, double(m.uvs[v].v) * n,
                   b.forward.x * p.x + b.forward.y * p.y + b.forward.z * p.z});
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Each triangle as its three (corner, depth-rounded) vertices, sorted, so
// that decoded meshes compare to the input whatever the vertex order.
std::vector<std::array<std::uint64_t, 3>> triangle_corners(const FaceMesh& m, int n) {
  std::vector<std::array<std::uint64_t, 3>> out;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    std::array<std::uint64_t, 3> tri;
    for (int k = 0; k < 3; ++k) {
      const Uv& uv = m.uvs[m.indices[3 * t + std::size_t(k)]];
      tri[std::size_t(k)] = std::uint64_t(std::lround(uv.u * n)) << 32 | std::uint64_t(std::lround(uv.v * n));
    }
    // Rotate (winding kept) so the smallest corner leads.
    const auto lead = std::min_element(tri.begin(), tri.end()) - tri.begin();
    std::rotate(tri.begin(), tri.begin() + lead, tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(GridMeshCodec, RoundTripKeepsCornersExactAndDepthWithinTheBound) {
  for (int face = 0; face < kCubeFaces; ++face)
    for (double error : {0.002, 0.001, 0.0001}) {
      const int n = 24;
      const FaceMesh m = ray_grid_mesh(face, n);
      const auto blob = encode_face_mesh(m, grid_params(face, n, error));
      ASSERT_EQ(blob[4], 2) << "grid meshes are written as version 2";
      const FaceMesh d = decode_face_mesh(blob);
      ASSERT_EQ(d.positions.size(), m.positions.size());
      ASSERT_EQ(d.uvs.size(), d.positions.size());
      const auto a = corners_and_depths(m, face, n), b = corners_and_depths(d, face, n);
      for (std::size_t v = 0; v < a.size(); ++v) {
        ASSERT_NEAR(a[v][0], b[v][0], 1e-4) << "pixel corners are exact (to float uv rounding)";
        ASSERT_NEAR(a[v][1], b[v][1], 1e-4);
        EXPECT_LE(std::fabs(b[v][2] - a[v][2]) / a[v][2], error * (1 + 1e-6) + 1e-7) << "face " << face;
      }
      EXPECT_EQ(triangle_corners(d, n), triangle_corners(m, n)) << "same triangles, same winding";
    }
}

TEST(GridMeshCodec, DecodedVerticesLieOnTheirPixelRays) {
  const int n = 16, face = 3;
  const FaceMesh d = decode_face_mesh(encode_face_mesh(ray_grid_mesh(face, n), grid_params(face, n)));
  const FaceBasis b = cube_face_basis(face);
  for (std::size_t v = 0; v < d.positions.size(); ++v) {
    const Vec3f& p = d.positions[v];
    const double z = b.forward.x * p.x + b.forward.y * p.y + b.forward.z * p.z;
    const Vec3d ray = cube_face_direction(b, 2.0 * d.uvs[v].u - 1, 1 - 2.0 * d.uvs[v].v) * z;
    EXPECT_LE(std::max({std::fabs(ray.x - p.x), std::fabs(ray.y - p.y), std::fabs(ray.z - p.z)}), 1e-6 * z);
  }
}

TEST(GridMeshCodec, SimplifiedDepthMeshesUseVersion2AndStayCrackFreeAcrossFaces) {
  // A sample inside a box room: planar walls, so the simplified meshes are small.
  const int n = 32;
  CubeSample sample;
  for (int f = 0; f < kCubeFaces; ++f) {
    CubeFace& face = sample.faces[std::size_t(f)];
    face.size = n;
    face.color.assign(std::size_t(n) * n, Rgba8{100, 120, 140, 255});
    face.depth.assign(std::size_t(n) * n, 2.0f + 0.5f * float(f));
  }
  const auto dense = build_depth_meshes(sample, {});
  std::array<FaceMesh, kCubeFaces> decoded;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceMesh simplified = simplify_face_mesh(dense[std::size_t(f)], n, {}).mesh;
    const auto blob = encode_face_mesh(simplified, grid_params(f, n));
    ASSERT_EQ(blob[4], 2) << "face " << f;
    MeshEncodeParams v1;
    EXPECT_LT(blob.size(), encode_face_mesh(simplified, v1).size());
    decoded[std::size_t(f)] = decode_face_mesh(blob);
  }
  // A vertex on a cube edge decodes to the same position in every face that has it.
  std::map<std::array<float, 3>, int> seen;
  std::size_t shared = 0;
  for (const FaceMesh& m : decoded)
    for (const Vec3f& p : m.positions) ++seen[{p.x, p.y, p.z}];
  for (const auto& [p, count] : seen) shared += count > 1;
  EXPECT_GE(shared, 8u) << "cube corners (at least) are shared bit for bit";
}

TEST(GridMeshCodec, MeshesOffTheGridFallBackToVersion1) {
  const FaceMesh m = grid_mesh(6, 5);  // not on any face's pixel rays
  EXPECT_EQ(encode_face_mesh(m, grid_params(0, 6))[4], 1);
  FaceMesh off = ray_grid_mesh(2, 8);
  off.positions[5].x += 0.01f;  // one vertex pushed off its ray
  EXPECT_EQ(encode_face_mesh(off, grid_params(2, 8))[4], 1);
  EXPECT_EQ(encode_face_mesh(ray_grid_mesh(2, 8), grid_params(3, 8))[4], 1) << "wrong face";
  EXPECT_EQ(encode_face_mesh(ray_grid_mesh(2, 8), grid_params(2, 8))[4], 2);
  const auto empty = encode_face_mesh(FaceMesh{}, grid_params(1, 8));
  EXPECT_EQ(empty[4], 2);
  EXPECT_TRUE(decode_face_mesh(empty).positions.empty());
}

TEST(GridMeshCodec, SameInputGivesSameBytes) {
  const FaceMesh m = ray_grid_mesh(4, 20);
  EXPECT_EQ(encode_face_mesh(m, grid_params(4, 20)), encode_face_mesh(m, grid_params(4, 20)));
}

// A version-1 blob as the encoder before issue #16 wrote it (two triangles,
// positions on face +Z's rays, 16 bits): old databases must keep decoding.
TEST(GridMeshCodec, Version1BlobsStillDecode) {
  const FaceMesh m = ray_grid_mesh(4, 1);
  MeshEncodeParams v1;
  v1.optimize_order = false;
  const std::vector<std::uint8_t> blob = encode_face_mesh(m, v1);
  const std::vector<std::uint8_t> fixture = {
      0x43, 0x42, 0x46, 0x4d, 0x01, 0x10, 0x10, 0x01, 0x04, 0x00, 0x00, 0x00,
      0x06, 0x00, 0x00, 0x00, 0xaf, 0x9d, 0x58, 0xc0, 0xde, 0x29, 0x58, 0xc0,
      0x00, 0x00, 0x40, 0x40, 0x00, 0x00, 0x40, 0x40, 0xaf, 0x9d, 0x58, 0x40,
      0xaf, 0x9d, 0x58, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x80, 0x3f, 0x5e, 0x00, 0x00, 0x00,
      0x16, 0x00, 0x00, 0x00, 0xa0, 0x01, 0x27, 0x00, 0x00, 0x00, 0x94, 0x01,
      0x26, 0x00, 0x00, 0x00, 0x01, 0x3f, 0x00, 0x00, 0x00, 0xdf, 0x98, 0x95,
      0x01, 0x3f, 0x00, 0x00, 0x00, 0x1c, 0x1e, 0x1b, 0x01, 0x1b, 0x00, 0x00,
      0x00, 0x96, 0x01, 0x1b, 0x00, 0x00, 0x00, 0x09, 0x01, 0x19, 0x00, 0x00,
      0x00, 0x01, 0x19, 0x00, 0x00, 0x00, 0x01, 0x04, 0x00, 0x00, 0x00, 0x01,
      0x04, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0xff, 0xff, 0x6f, 0xf1, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
      0x00, 0x00, 0xe0, 0xfe, 0x00, 0xff, 0x04, 0x02, 0x00, 0x76, 0x87, 0x56,
      0x67, 0x78, 0xa9, 0x86, 0x65, 0x89, 0x68, 0x98, 0x01, 0x69, 0x00, 0x00};
  EXPECT_EQ(blob, fixture) << "the version-1 writer is unchanged";
  const FaceMesh d = decode_face_mesh(fixture);
  ASSERT_EQ(d.positions.size(), 4u);
  ASSERT_EQ(d.indices, m.indices);
  const double bound = face_mesh_position_error_bound(m, 16);
  for (std::size_t v = 0; v < 4; ++v) {
    EXPECT_NEAR(d.positions[v].x, m.positions[v].x, bound);
    EXPECT_NEAR(d.positions[v].y, m.positions[v].y, bound);
    EXPECT_NEAR(d.positions[v].z, m.positions[v].z, bound);
    EXPECT_NEAR(d.uvs[v].u, m.uvs[v].u, 1e-4);
  }
}

TEST(GridMeshCodec, CorruptBlobsAreRejectedWithoutCrashing) {
  const auto good = encode_face_mesh(ray_grid_mesh(0, 10), grid_params(0, 10));
  ASSERT_EQ(good[4], 2);
  for (std::size_t len = 0; len < good.size(); ++len)
    EXPECT_THROW(decode_face_mesh(good.data(), len), std::runtime_error) << "length " << len;
  for (std::size_t bit = 0; bit < good.size() * 8; ++bit) {
    auto bad = good;
    bad[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    expect_mesh_decode_safe(bad.data(), bad.size());
  }
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5000; ++trial) {
    auto bad = good;
    const int edits = 1 + static_cast<int>(rng() % 6);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % bad.size();
      if (rng() % 2) bad[at] = static_cast<std::uint8_t>(rng());
      else if (bad.size() > 1) bad.erase(bad.begin() + static_cast<std::ptrdiff_t>(at));
    }
    expect_mesh_decode_safe(bad.data(), bad.size());
  }
  // A lying vertex count, an unknown face, noise behind a valid header.
  auto lie = good;
  lie[12] = lie[13] = lie[14] = lie[15] = 0xff;
  EXPECT_THROW(decode_face_mesh(lie), std::runtime_error);
  lie = good;
  lie[5] = 6;
  EXPECT_THROW(decode_face_mesh(lie), std::runtime_error);
  for (int trial = 0; trial < 1000; ++trial) {
    std::vector<std::uint8_t> framed(good.begin(), good.begin() + 48);
    for (std::size_t k = rng() % 300; k > 0; --k) framed.push_back(static_cast<std::uint8_t>(rng()));
    expect_mesh_decode_safe(framed.data(), framed.size());
  }
}

}  // namespace
}  // namespace cellbake
