// Geometry store: blob codec round trips and corruption safety, R*Tree queries,
// atomic replacement, metadata.
#include <gtest/gtest.h>

#include <cstring>

#include <random>

#include "storage/chunk_codec.h"
#include "storage/geometry_store.h"
#include "test_support.h"

namespace cellbake {
namespace {

Chunk make_chunk(unsigned seed, Vec3d origin, bool uvs, bool materials) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  Chunk c;
  c.origin = origin;
  const int nv = 200;
  for (int i = 0; i < nv; ++i) {
    c.positions.push_back({u(rng), u(rng), u(rng)});
    c.colors.push_back({std::uint8_t(rng()), std::uint8_t(rng()), std::uint8_t(rng()), 255});
    if (uvs) c.uvs.push_back({u(rng), u(rng)});
  }
  for (int t = 0; t < 300; ++t) {
    for (int k = 0; k < 3; ++k) c.indices.push_back(rng() % nv);
    if (materials) c.materials.push_back(rng() % 4);
  }
  for (const auto& p : c.positions) c.bounds.expand(origin + Vec3d{p.x, p.y, p.z});
  return c;
}

void expect_same_geometry(const Chunk& a, const Chunk& b) {
  ASSERT_EQ(a.triangle_count(), b.triangle_count());
  for (std::size_t i = 0; i < a.indices.size(); i += 3) {
    // The index codec may rotate a triangle's corners (winding kept): compare as rotations.
    bool match = false;
    for (int r = 0; r < 3 && !match; ++r) {
      match = true;
      for (int k = 0; k < 3; ++k) {
        const auto ia = a.indices[i + k], ib = b.indices[i + (k + r) % 3];
        match &= a.positions[ia] == b.positions[ib] && a.colors[ia] == b.colors[ib];
        if (!a.uvs.empty()) match &= a.uvs[ia] == b.uvs[ib];
      }
    }
    EXPECT_TRUE(match) << "triangle " << i / 3;
  }
  EXPECT_EQ(a.materials, b.materials);
}

TEST(ChunkCodec, RoundTripWithAndWithoutOptionalAttributes) {
  for (bool uvs : {false, true})
    for (bool mats : {false, true}) {
      Chunk c = make_chunk(7, {1, 2, 3}, uvs, mats);
      auto blob = encode_chunk_blob(c);
      Chunk d;
      decode_chunk_blob(blob.data(), blob.size(), d);
      expect_same_geometry(c, d);
      EXPECT_EQ(encode_chunk_blob(c), blob);  // deterministic
    }
}

TEST(ChunkCodec, RejectsCorruptBlobsWithoutCrashing) {
  Chunk c = make_chunk(9, {0, 0, 0}, true, true);
  const auto blob = encode_chunk_blob(c);
  std::mt19937 rng(123);
  int rejected = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    auto bad = blob;
    const int mode = trial % 3;
    if (mode == 0) bad.resize(rng() % blob.size());
    if (mode == 1)
      for (int f = 0; f < 1 + int(rng() % 4); ++f) bad[rng() % bad.size()] ^= std::uint8_t(1u << (rng() % 8));
    if (mode == 2)
      for (auto& b : bad) b = std::uint8_t(rng());
    Chunk d;
    try {
      decode_chunk_blob(bad.data(), bad.size(), d);
      for (auto i : d.indices) ASSERT_LT(i, d.positions.size());
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("chunk blob"), std::string::npos);
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 1500);
  Chunk d;
  EXPECT_THROW(decode_chunk_blob(nullptr, 0, d), std::runtime_error);
}

// Found by tests/fuzz/fuzz_chunk_codec: a blob of a few bytes claiming 2^24
// vertices made the decoder allocate ~600 MB before it looked at the data.
TEST(ChunkCodec, CountsTheDataCannotHoldAreRejectedBeforeAllocating) {
  const auto blob = encode_chunk_blob(make_chunk(1, {0, 0, 0}, false, false));
  for (const std::uint32_t nv : {1u << 24, 1u << 20}) {
    std::vector<std::uint8_t> bad(blob.begin(), blob.begin() + 16);  // magic, version, flags, counts
    std::memcpy(bad.data() + 8, &nv, 4);
    const std::uint32_t ni = 3 * nv, vbytes = 20, ibytes = 20;
    std::memcpy(bad.data() + 12, &ni, 4);
    bad.insert(bad.end(), reinterpret_cast<const std::uint8_t*>(&vbytes), reinterpret_cast<const std::uint8_t*>(&vbytes) + 4);
    bad.insert(bad.end(), vbytes, 0);
    bad.insert(bad.end(), reinterpret_cast<const std::uint8_t*>(&ibytes), reinterpret_cast<const std::uint8_t*>(&ibytes) + 4);
    bad.insert(bad.end(), ibytes, 0);
    Chunk d;
    try {
      decode_chunk_blob(bad.data(), bad.size(), d);
      ADD_FAILURE() << "accepted " << nv << " vertices in " << bad.size() << " bytes";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("vertex data too short"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(d.positions.empty());
  }
}

// Found by tests/fuzz/fuzz_chunk_codec: an empty chunk flagged as having
// materials, uvs and normals copied zero material bytes from a null pointer
// (undefined behaviour).
TEST(ChunkCodec, AnEmptyChunkWithEveryFlagDecodes) {
  const std::uint8_t input[] = {0x43, 0x42, 0x43, 0x4b, 0x1, 0x0, 0x7, 0x0, 0x0, 0x0, 0x0,  0x0,  0x0, 0x0, 0x0, 0x0, 0x0,
                                0x0,  0x0,  0x0,  0x0,  0x0, 0x0, 0x0, 0x0, 0x0, 0xff, 0xff, 0x0, 0xc, 0x5b, 0x0, 0x0};
  Chunk d;
  try {
    decode_chunk_blob(input, sizeof input, d);
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(d.triangle_count(), 0u);
}

TEST(GeometryStore, WritesQueriesAndLoads) {
  test::TempDir dir;
  const auto path = dir / "store.db";
  {
    GeometryStoreWriter w(path);
    for (int i = 0; i < 10; ++i) w.add_chunk(make_chunk(i, {10.0 * i, 0, 1e6}, false, false));
    StoreSummary s;
    s.bounds = {{-1, -1, 1e6 - 1}, {91, 1, 1e6 + 1}};
    s.triangles = 3000;
    s.chunks = 10;
    s.content_hash = "abc";
    w.finish(s);
  }
  GeometryStore store(path);
  EXPECT_EQ(store.summary().chunks, 10u);
  EXPECT_EQ(store.summary().content_hash, "abc");
  EXPECT_EQ(store.model_bounds().hi.x, 91);
  auto hits = store.query({{15, -5, 1e6 - 5}, {35, 5, 1e6 + 5}});
  ASSERT_EQ(hits.size(), 2u);  // chunks centred at x = 20 and x = 30
  EXPECT_EQ(hits[0].id, 3);
  EXPECT_EQ(hits[1].id, 4);
  EXPECT_EQ(hits[0].triangle_count, 300u);
  auto chunk = store.load(3);
  EXPECT_EQ(chunk->origin.x, 20.0);
  EXPECT_EQ(chunk->origin.z, 1e6);
  expect_same_geometry(make_chunk(2, {20, 0, 1e6}, false, false), *chunk);
  EXPECT_EQ(store.load(3).get(), chunk.get());  // cached
  EXPECT_THROW(store.load(99), std::runtime_error);
  EXPECT_TRUE(store.query({{500, 500, 500}, {600, 600, 600}}).empty());
}

TEST(GeometryStore, UnfinishedWriterLeavesExistingStoreUntouched) {
  test::TempDir dir;
  const auto path = dir / "store.db";
  {
    GeometryStoreWriter w(path);
    w.add_chunk(make_chunk(1, {0, 0, 0}, false, false));
    StoreSummary s;
    s.triangles = 300;
    s.chunks = 1;
    s.bounds = {{-1, -1, -1}, {1, 1, 1}};
    w.finish(s);
  }
  {
    GeometryStoreWriter w(path);  // abandoned: simulated failure mid-ingest
    w.add_chunk(make_chunk(2, {0, 0, 0}, false, false));
    w.add_chunk(make_chunk(3, {0, 0, 0}, false, false));
  }
  GeometryStore store(path);
  EXPECT_EQ(store.summary().chunks, 1u);
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1u);  // no temporary file left behind
}

TEST(GeometryStore, RejectsFilesThatAreNotStores) {
  test::TempDir dir;
  test::write_text(dir / "junk.db", "this is not sqlite");
  EXPECT_THROW(GeometryStore(dir / "junk.db"), std::runtime_error);
  EXPECT_THROW(GeometryStore(dir / "missing.db"), std::runtime_error);
}

}  // namespace
}  // namespace cellbake
