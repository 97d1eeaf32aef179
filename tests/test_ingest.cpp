// Ingest end to end: counts and skips, chunk invariants, determinism across
// thread counts, far-from-origin precision, and bad input that must leave an
// existing store untouched (through the real `cellbake ingest` command).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "pipeline/ingest.h"
#include "runner/parallel.h"
#include "stages/hashing.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "test_support.h"
#include "tests/fixture_textured.h"

namespace cellbake {
namespace {

ParallelFor serial() {
  return [](std::size_t n, const std::function<void(std::size_t)>& fn) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
  };
}

// A height field of n x n quads (2 n^2 triangles) plus extra lines appended.
std::string grid_obj(int n, const std::string& extra = "") {
  std::ostringstream o;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) o << "v " << i * 0.25 << " " << j * 0.25 << " " << ((i * 7 + j * 3) % 5) * 0.125 << "\n";
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
      o << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
    }
  o << extra;
  return o.str();
}

std::string file_hash(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return hash_hex(bytes.data(), bytes.size());
}

TEST(Ingest, CountsSkipsAndChunkInvariants) {
  test::TempDir dir;
  // Two degenerate triangles (repeated corner, collinear) and one duplicate of the first face.
  test::write_text(dir / "m.obj", grid_obj(60, "f 1 1 2\nv 0 0 9\nv 1 0 9\nv 2 0 9\nf -1 -2 -3\nf 2 63 1\n"));
  IngestParams params;
  params.max_chunk_triangles = 500;
  const IngestReport r = ingest_models({dir / "m.obj"}, dir / "s.db", params, serial());
  EXPECT_EQ(r.triangles_read, 2u * 60 * 60 + 3);
  EXPECT_EQ(r.skipped_degenerate, 2u);
  EXPECT_EQ(r.skipped_duplicate, 1u);
  EXPECT_EQ(r.triangles_stored, 2u * 60 * 60);

  GeometryStore store(dir / "s.db");
  EXPECT_EQ(store.summary().triangles, r.triangles_stored);
  EXPECT_EQ(store.summary().skipped_duplicate, 1u);
  std::uint64_t total = 0;
  for (const ChunkRef& ref : store.all_chunks()) {
    EXPECT_LE(ref.triangle_count, 500u);
    EXPECT_GT(ref.triangle_count, 100u);
    auto chunk = store.load(ref.id);
    EXPECT_EQ(chunk->triangle_count(), ref.triangle_count);
    total += chunk->triangle_count();
    for (std::size_t v = 0; v < chunk->positions.size(); ++v) {
      const Vec3d w = chunk->world(std::uint32_t(v));
      EXPECT_TRUE(ref.bounds.contains(Box3d{w, w}));
    }
    // The R*Tree finds the chunk by its own bounds.
    bool found = false;
    for (const auto& q : store.query(ref.bounds)) found |= q.id == ref.id;
    EXPECT_TRUE(found);
  }
  EXPECT_EQ(total, r.triangles_stored);
  ASSERT_EQ(store.sources().size(), 1u);
  EXPECT_EQ(store.sources()[0].triangles, r.triangles_stored + 1);  // duplicates are found after reading
}

TEST(Ingest, SameChunksWhateverTheThreadCount) {
  test::TempDir dir;
  test::write_text(dir / "m.obj", grid_obj(80));
  IngestParams params;
  params.max_chunk_triangles = 256;
  const IngestReport a = ingest_models({dir / "m.obj"}, dir / "a.db", params, serial());
  const IngestReport b = ingest_models({dir / "m.obj"}, dir / "b.db", params, tbb_parallel_for());
  EXPECT_EQ(a.content_hash, b.content_hash);
  GeometryStore sa(dir / "a.db"), sb(dir / "b.db");
  auto ca = sa.all_chunks(), cb = sb.all_chunks();
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i) {
    auto x = sa.load(ca[i].id), y = sb.load(cb[i].id);
    EXPECT_EQ(x->positions, y->positions);
    EXPECT_EQ(x->indices, y->indices);
    EXPECT_EQ(x->origin, y->origin);
  }
}

// The store's content hash is over what the store holds, so everything that
// reaches it through any file (the .mtl's colours, a texture's texels, the
// geometry) changes it, and nothing else does (the model file's other bytes,
// the recorded up axis). GeometryStoreWriter's hash equals the one recomputed
// from the finished file.
TEST(Ingest, TheStoreHashCoversMaterialsTexturesAndGeometryAsStored) {
  test::TempDir dir;
  const auto texels = test::checker_texels(2, 2);  // 4 x 4
  test::write_png_bottom_up(dir / "tex.png", texels, 4, 4);
  const auto wall = [&](const std::string& kd, const test::TexturedQuad& quad = test::checker_wall()) {
    return test::write_textured_quad_obj(dir.path(), "wall", quad, "wall", "tex.png", kd);
  };
  const auto obj = wall("1 0 0");
  int stores = 0;
  const auto ingest = [&](IngestParams params = {}) {
    const auto store = dir / ("s" + std::to_string(++stores) + ".db");
    const IngestReport r = ingest_models({obj}, store, params, serial());
    EXPECT_EQ(r.textures, 1u);
    EXPECT_EQ(GeometryStore(store).summary().content_hash, r.content_hash);
    EXPECT_EQ(stored_content_hash(store), r.content_hash) << "recomputed from the rows of " << store;
    return r.content_hash;
  };
  const std::string first = ingest();
  EXPECT_EQ(ingest(), first) << "deterministic";

  wall("0 1 0");  // a material colour in the .mtl
  EXPECT_NE(ingest(), first);
  wall("1 0 0");
  EXPECT_EQ(ingest(), first);

  auto changed = texels;  // one texel of the texture
  changed[5].r ^= 1;
  test::write_png_bottom_up(dir / "tex.png", changed, 4, 4);
  EXPECT_NE(ingest(), first);
  test::write_png_bottom_up(dir / "tex.png", texels, 4, 4);

  test::TexturedQuad moved = test::checker_wall();  // the geometry
  moved.c11.z += 0.25;
  wall("1 0 0", moved);
  EXPECT_NE(ingest(), first);
  wall("1 0 0");

  { std::ofstream(obj, std::ios::app) << "# the same model in other bytes\n"; }
  IngestParams y_up;
  y_up.up = "y";
  EXPECT_EQ(ingest(y_up), first) << "file bytes that store nothing and the up axis are not content";
}

// The regression: a bake redoes its cells when only a .mtl colour changed and
// the model was ingested again (the store hash used to cover the model files'
// bytes alone, so the cells' input hashes stayed and the bake skipped them).
TEST(Ingest, ABakeRedoesItsCellsAfterAMaterialColourChanged) {
  test::TempDir dir;
  test::write_png_bottom_up(dir / "tex.png", test::checker_texels(2, 2), 4, 4);
  const auto obj = test::write_textured_quad_obj(dir.path(), "wall", test::checker_wall(), "wall", "tex.png", "1 0 0");
  const std::string bake = "bake --store " + (dir / "s.db").string() + " --out " + (dir / "cells.db").string() +
                           " --region=2,5.5,1,3.5,6.5,2 --cell-size 1 --face-size 16 --quiet --threads 1";
  ingest_models({obj}, dir / "s.db", IngestParams{}, serial());
  const auto first = test::run_cellbake(bake);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const auto input_hashes = [&] {
    std::vector<std::string> hashes;
    CellDb cells(dir / "cells.db", CellDb::Mode::read_only);
    for (std::int64_t id : cells.cell_ids()) hashes.push_back(cells.get_cell(id, false)->input_hash);
    return hashes;
  };
  const std::vector<std::string> before = input_hashes();
  ASSERT_FALSE(before.empty());

  test::write_textured_quad_obj(dir.path(), "wall", test::checker_wall(), "wall", "tex.png", "0 0 1");
  ingest_models({obj}, dir / "s.db", IngestParams{}, serial());
  const auto again = test::run_cellbake(bake);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const std::vector<std::string> after = input_hashes();
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) EXPECT_NE(after[i], before[i]) << "cell " << i << " was not redone";
}

TEST(Ingest, SpillFileGivesTheSameStoreAsMemory) {
  test::TempDir dir;
  test::write_text(dir / "m.obj", grid_obj(50));
  IngestParams params;
  params.max_chunk_triangles = 300;
  const IngestReport a = ingest_models({dir / "m.obj"}, dir / "mem.db", params, serial());
  params.memory_budget_bytes = 100 * sizeof(Triangle);  // spills after 100 triangles
  params.temp_dir = dir / "spill";
  const IngestReport b = ingest_models({dir / "m.obj"}, dir / "file.db", params, tbb_parallel_for());
  EXPECT_EQ(a.content_hash, b.content_hash);
  GeometryStore sa(dir / "mem.db"), sb(dir / "file.db");
  auto ca = sa.all_chunks(), cb = sb.all_chunks();
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i) {
    EXPECT_EQ(sa.load(ca[i].id)->positions, sb.load(cb[i].id)->positions);
    EXPECT_EQ(sa.load(ca[i].id)->indices, sb.load(cb[i].id)->indices);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir / "spill"));  // the spill file is gone
}

TEST(Ingest, FarFromOriginKeepsChunkGeometry) {
  test::TempDir dir;
  test::write_text(dir / "m.obj", grid_obj(40));
  IngestParams params;
  params.max_chunk_triangles = 300;
  ingest_models({dir / "m.obj"}, dir / "near.db", params, serial());
  params.translate = {1e6, -3e6, 2e5};
  ingest_models({dir / "m.obj"}, dir / "far.db", params, serial());
  GeometryStore a(dir / "near.db"), b(dir / "far.db");
  auto ca = a.all_chunks(), cb = b.all_chunks();
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i) {
    auto x = a.load(ca[i].id), y = b.load(cb[i].id);
    ASSERT_EQ(x->indices, y->indices);
    EXPECT_NEAR(y->origin.x - x->origin.x, 1e6, 1e-6);
    for (std::size_t v = 0; v < x->positions.size(); ++v) {
      // Sub-micrometre agreement of local coordinates (float rounding of values < ~10 m).
      EXPECT_NEAR(x->positions[v].x, y->positions[v].x, 1e-6);
      EXPECT_NEAR(x->positions[v].y, y->positions[v].y, 1e-6);
      EXPECT_NEAR(x->positions[v].z, y->positions[v].z, 1e-6);
    }
  }
}

struct BadInput {
  std::string name, content, expect_in_message;
};

TEST(Ingest, BadInputFailsClearlyAndLeavesTheStoreUntouched) {
  test::TempDir dir;
  test::write_text(dir / "good.obj", grid_obj(10));
  auto ok = test::run_cellbake("ingest " + (dir / "good.obj").string() + " --store " + (dir / "s.db").string());
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("ingested 200 triangles"), std::string::npos) << ok.output;
  const std::string before = file_hash(dir / "s.db");
  const std::vector<BadInput> cases = {
      {"nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n", "nan.obj:line 2"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "range.obj:line 4"},
      {"empty.obj", "# nothing here\n", "no triangles"},
      {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "degenerate"},
      {"junk.ply", "ply\nformat ascii 1.0\nelement vertex two\nend_header\n", "junk.ply"},
      {"short.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\x01\x02",
       "short.ply"},
      {"model.xyz", "1 2 3\n", "unknown model format"},
  };
  for (const auto& c : cases) {
    test::write_text(dir / c.name, c.content);
    auto r = test::run_cellbake("ingest " + (dir / c.name).string() + " --store " + (dir / "s.db").string());
    EXPECT_NE(r.exit_code, 0) << c.name;
    EXPECT_NE(r.output.find(c.expect_in_message), std::string::npos) << c.name << ": " << r.output;
    EXPECT_EQ(file_hash(dir / "s.db"), before) << c.name;
  }
  auto missing = test::run_cellbake("ingest " + (dir / "absent.obj").string() + " --store " + (dir / "s.db").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("absent.obj"), std::string::npos) << missing.output;
  // No temporary or spill files are left behind.
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << e.path();
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().string().find(".spill-"), std::string::npos) << e.path();
}

// A kitchen-style OBJ: "v x y z 0 0 0" on every vertex (an exporter's
// default) and a red material. The store holds red, not black, and the ingest
// summary says which colours were used.
TEST(Ingest, UniformVertexColoursGiveWayToMaterialsAndTheSummarySaysSo) {
  test::TempDir dir;
  test::write_text(dir / "k.mtl", "newmtl red\nKd 0.8 0 0\n");
  std::ostringstream obj;
  obj << "mtllib k.mtl\nusemtl red\n";
  for (int i = 0; i < 4; ++i) obj << "v " << i % 2 << " " << i / 2 << " 0 0 0 0\n";
  obj << "f 1 2 4\nf 1 4 3\n";
  test::write_text(dir / "kitchen.obj", obj.str());
  auto r = test::run_cellbake("ingest " + (dir / "kitchen.obj").string() + " --store " + (dir / "s.db").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("kitchen.obj: vertex colours: ignored (all equal: 0 0 0), material colours used"),
            std::string::npos)
      << r.output;
  GeometryStore store(dir / "s.db");
  std::size_t colours = 0;
  for (const ChunkRef& ref : store.all_chunks())
    for (const Rgba8& c : store.load(ref.id)->colors) {
      EXPECT_EQ(c, (Rgba8{204, 0, 0, 255}));
      ++colours;
    }
  EXPECT_GT(colours, 0u);
}

}  // namespace
}  // namespace cellbake
