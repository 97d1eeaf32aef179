// The far geometry's triangle-number coding (stages/encode/encode_triangle_list.h)
// and the viewer's cut of a far piece out of its stored chunk.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "stages/encode/encode_triangle_list.h"
#include "tests/fixture_memory_chunk_source.h"
#include "viewer/decoded_cell.h"

namespace cellbake {
namespace {

std::vector<std::uint32_t> round_trip(const std::vector<std::uint32_t>& list) {
  return decode_triangle_list(encode_triangle_list(list));
}

TEST(TriangleList, RoundTripsEdgeCases) {
  EXPECT_TRUE(round_trip({}).empty());
  const std::vector<std::vector<std::uint32_t>> cases = {
      {0}, {5}, {0, 1, 2, 3}, {1, 3, 5, 7}, {0, 2, 3, 4, 9}, {kMaxTriangleListIndex - 1}, {0, kMaxTriangleListIndex - 1}};
  for (const auto& c : cases) EXPECT_EQ(round_trip(c), c);
}

TEST(TriangleList, RunsCostAboutTwoBytesEach) {
  std::vector<std::uint32_t> all(4096);
  for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  // Header (5) + count (2) + one run (gap 1 byte, length 2 bytes).
  EXPECT_EQ(encode_triangle_list(all).size(), 5u + 2u + 3u);
  std::vector<std::uint32_t> runs;  // 64 runs of 10 with gaps of 20
  for (std::uint32_t r = 0; r < 64; ++r)
    for (std::uint32_t i = 0; i < 10; ++i) runs.push_back(30 * r + i);
  EXPECT_EQ(encode_triangle_list(runs).size(), 5u + 2u + 64u * 2u);
}

TEST(TriangleList, RandomSubsetsRoundTripDeterministically) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<std::uint32_t> list;
    const double keep = std::uniform_real_distribution<double>(0.01, 0.99)(rng);
    for (std::uint32_t t = 0; t < 4096; ++t)
      if (std::bernoulli_distribution(keep)(rng)) list.push_back(t);
    const auto bytes = encode_triangle_list(list);
    EXPECT_EQ(bytes, encode_triangle_list(list));
    EXPECT_EQ(decode_triangle_list(bytes), list);
  }
}

TEST(TriangleList, EncoderRefusesUnorderedOrOutOfRangeNumbers) {
  EXPECT_THROW(encode_triangle_list(std::vector<std::uint32_t>{3, 2}), std::invalid_argument);
  EXPECT_THROW(encode_triangle_list(std::vector<std::uint32_t>{2, 2}), std::invalid_argument);
  EXPECT_THROW(encode_triangle_list(std::vector<std::uint32_t>{kMaxTriangleListIndex}), std::invalid_argument);
  EXPECT_THROW(encode_triangle_list(std::vector<std::uint32_t>{kMaxTriangleListIndex - 1, kMaxTriangleListIndex}),
               std::invalid_argument);
}

TEST(TriangleList, DecoderRejectsEveryTruncationAndBadHeader) {
  std::vector<std::uint32_t> list;
  for (std::uint32_t t = 0; t < 3000; t += 7) list.push_back(t);
  const auto bytes = encode_triangle_list(list);
  for (std::size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(decode_triangle_list(std::span(bytes.data(), n)), std::runtime_error) << n;
  auto trailing = bytes;
  trailing.push_back(0);
  EXPECT_THROW(decode_triangle_list(trailing), std::runtime_error);
  auto version = bytes;
  version[4] = 9;
  EXPECT_THROW(decode_triangle_list(version), std::runtime_error);
  auto magic = bytes;
  magic[0] ^= 1;
  EXPECT_FALSE(is_triangle_list_blob(magic));
  EXPECT_THROW(decode_triangle_list(magic), std::runtime_error);
}

TEST(TriangleList, DecoderRejectsEmptyRunsOverlongVarintsAndHugeCounts) {
  const std::vector<std::uint8_t> head = {'C', 'B', 'T', 'L', 1};
  auto with = [&](std::vector<std::uint8_t> tail) {
    auto b = head;
    b.insert(b.end(), tail.begin(), tail.end());
    return b;
  };
  EXPECT_THROW(decode_triangle_list(with({2, 0, 0})), std::runtime_error);                          // empty run
  EXPECT_THROW(decode_triangle_list(with({0x80, 0x80, 0x80, 0x80, 0x80, 0x01})), std::runtime_error);  // overlong
  EXPECT_THROW(decode_triangle_list(with({0xff, 0xff, 0xff, 0xff, 0x0f})), std::runtime_error);     // count > limit
  EXPECT_THROW(decode_triangle_list(with({2, 0, 3})), std::runtime_error);                          // run > count
  // A run past the limit.
  EXPECT_THROW(decode_triangle_list(with({1, 0x80, 0x80, 0x80, 0x20, 1})), std::runtime_error);
  EXPECT_EQ(decode_triangle_list(with({2, 3, 2})), (std::vector<std::uint32_t>{3, 4}));
}

TEST(TriangleList, RandomBytesNeverCrashTheDecoder) {
  std::mt19937 rng(11);
  std::vector<std::uint32_t> list;
  for (std::uint32_t t = 0; t < 4096; t += 3) list.push_back(t);
  const auto good = encode_triangle_list(list);
  for (int trial = 0; trial < 2000; ++trial) {
    auto b = good;
    const int flips = 1 + int(rng() % 4);
    for (int k = 0; k < flips; ++k) b[5 + rng() % (b.size() - 5)] = static_cast<std::uint8_t>(rng());
    try {
      const auto out = decode_triangle_list(b);
      for (std::size_t i = 1; i < out.size(); ++i) ASSERT_LT(out[i - 1], out[i]);
    } catch (const std::runtime_error&) {
    }
  }
}

Chunk two_triangle_chunk() {
  Chunk c;
  c.id = 4;
  c.origin = {100, 0, 0};
  c.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}, {6, 5, 5}, {5, 6, 5}};
  c.colors.assign(6, Rgba8{10, 20, 30, 255});
  c.indices = {0, 1, 2, 3, 4, 5};
  c.materials = {0, 1};
  for (std::uint32_t v = 0; v < 6; ++v) c.bounds.expand(c.world(v));
  return c;
}

// A source holding two_triangle_chunk() as chunk 4.
std::unique_ptr<test::MemoryChunkSource> two_triangle_source() {
  auto source = std::make_unique<test::MemoryChunkSource>();
  source->add(two_triangle_chunk());
  return source;
}

TEST(FarPieceChunk, CutsTheStoredTrianglesUnderTheCacheId) {
  DecodedFarPiece piece;
  piece.cache_id = -7;
  piece.chunk_id = 4;
  piece.triangles = {1};
  const auto chunk = far_piece_chunk(piece, *two_triangle_source());
  EXPECT_EQ(chunk->id, -7);
  ASSERT_EQ(chunk->triangle_count(), 1u);
  EXPECT_EQ(chunk->positions.size(), 3u);
  EXPECT_EQ(chunk->materials, (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(chunk->bounds.lo, (Vec3d{105, 5, 5}));
}

TEST(FarPieceChunk, NumbersBeyondTheStoredChunkNameIt) {
  DecodedFarPiece piece;
  piece.cache_id = -7;
  piece.chunk_id = 4;
  piece.triangles = {1, 2};
  try {
    far_piece_chunk(piece, *two_triangle_source());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("chunk 4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cellbake
