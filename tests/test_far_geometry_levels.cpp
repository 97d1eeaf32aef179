// Far geometry rows that draw a simplified level of their chunk (issue #35):
// the cell database's `level` column, the content hash (unchanged for level 0),
// check_cell against a source's levels, and the viewer's decoded pieces.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "stages/encode/encode_triangle_list.h"
#include "stages/render/gl_context.h"
#include "storage/cell_check.h"
#include "storage/cell_content_hash.h"
#include "storage/cell_db.h"
#include "storage/cell_db_merge.h"
#include "tests/fixture_cameras.h"
#include "tests/fixture_memory_chunk_source.h"
#include "tests/test_support.h"
#include "viewer/decoded_cell.h"
#include "viewer/image_metrics.h"
#include "viewer/scene_drawer.h"

namespace cellbake {
namespace {

// A fixed done cell with every part the content hash reads: a near list, one
// sample with one face, far geometry rows (a whole chunk, a triangle list) and
// a far choice row.
CellRow fixed_cell() {
  CellRow row;
  row.id = 42;
  row.status = "done";
  row.bounds = {{0, 0, 0}, {2, 2, 2}};
  row.cull_half_size = 1.5;
  row.near_triangles = 10;
  row.near_chunks = {{3, 10, true}};
  SampleRow s;
  s.index = 0;
  s.eye = {1, 1, 1};
  s.void_after = 0.25;
  s.covered_pixels = 100;
  s.removed_pixels = 4;
  FaceRow f;
  f.face = 2;
  f.image_format = "png";
  f.image = {1, 2, 3};
  f.mesh = {4, 5};
  s.faces.push_back(f);
  row.samples.push_back(s);
  FarGeometryRow whole;
  whole.chunk_id = 7;
  whole.triangles = 12;
  whole.whole = true;
  whole.origin = {10, 20, 30};
  whole.bounds = {{10, 20, 30}, {11, 21, 31}};
  FarGeometryRow list;
  list.chunk_id = 9;
  list.triangles = 2;
  list.origin = {5, 6, 7};
  list.bounds = {{5, 6, 7}, {6, 7, 8}};
  list.geometry = {8, 9, 10};
  row.far_geometry = {whole, list};
  row.far_geometry_triangles = 14;
  row.far_choice.push_back({2, 0x8001u, 10, 4, 14});
  return row;
}

TEST(FarGeometryLevels, ContentHashOfLevelZeroRowsIsUnchanged) {
  // Computed by cell_content_hash on main before the level column (6f813e7):
  // every cell baked before issue #35 keeps its stored content hash.
  EXPECT_EQ(cell_content_hash(fixed_cell()), "8eb6ead250a351dd977710e8f5bd276d");
}

TEST(FarGeometryLevels, ALevelChangesTheContentHash) {
  CellRow row = fixed_cell();
  const std::string level0 = cell_content_hash(row);
  row.far_geometry[0].level = 1;
  const std::string level1 = cell_content_hash(row);
  row.far_geometry[0].level = 2;
  EXPECT_NE(level1, level0);
  EXPECT_NE(cell_content_hash(row), level1);
}

constexpr std::int64_t kChunk = 5;
const Vec3d kChunkOrigin{100, 0, 0};

// Chunk 5: a red 2 x 2 square of four triangles at z = 0 around (101, 1, 0);
// its level 1: two green triangles over the same square, level 2: one.
void add_chunk_with_levels(test::MemoryChunkSource& source) {
  const auto paint = [](Chunk c, Rgba8 colour) {
    for (Rgba8& v : c.colors) v = colour;
    return c;
  };
  const Vec3d a{100, 0, 0}, b{102, 0, 0}, c{102, 2, 0}, d{100, 2, 0}, m{101, 1, 0};
  source.add(
      paint(test::make_memory_chunk(kChunk, {{a, b, m}, {b, c, m}, {c, d, m}, {d, a, m}}, kChunkOrigin),
            {255, 0, 0, 255}));
  source.add_lod(
      kChunk, 1,
      paint(test::make_memory_chunk(kChunk, {{a, b, c}, {a, c, d}}, kChunkOrigin), {0, 255, 0, 255}), 0.01);
  source.add_lod(kChunk, 2,
                 paint(test::make_memory_chunk(kChunk, {{a, b, c}}, kChunkOrigin), {0, 0, 255, 255}), 0.5);
}

// A source holding chunk 5 and its levels.
struct SourceWithLevels : test::MemoryChunkSource {
  SourceWithLevels() { add_chunk_with_levels(*this); }
};

// Level `level` of chunk 5 as the bake writes it: whole, no blob, the level's
// triangles, the chunk's bounds.
FarGeometryRow level_row(const ChunkSource& source, int level) {
  FarGeometryRow g;
  g.chunk_id = kChunk;
  g.level = level;
  g.whole = true;
  g.bounds = source.load(kChunk)->bounds;
  for (const ChunkLodRef& l : source.lods(kChunk))
    if (l.level == level) g.triangles = l.triangle_count;
  return g;
}

// A done cell without samples far from chunk 5 (its cull box meets nothing)
// whose far geometry is `rows`, stamped with its content hash.
CellRow cell_with(std::int64_t id, std::vector<FarGeometryRow> rows) {
  CellRow row;
  row.id = id;
  row.status = "done";
  row.bounds = {{0, 0, 10}, {2, 2, 12}};
  row.cull_half_size = 0.5;
  row.input_hash = row.cull_hash = "h";
  for (const FarGeometryRow& g : rows) row.far_geometry_triangles += g.triangles;
  row.far_geometry = std::move(rows);
  row.content_hash = cell_content_hash(row);
  return row;
}

TEST(FarGeometryLevels, ALevelRowRoundTripsThroughTheCellDatabase) {
  test::TempDir dir;
  const SourceWithLevels source;
  FarGeometryRow whole = level_row(source, 1);
  whole.level = 0;
  whole.chunk_id = 3;
  whole.triangles = 4;
  {
    CellDb db(dir / "cells.db", CellDb::Mode::read_write);
    EXPECT_EQ(db.schema_version(), 5);
    db.put_cell(cell_with(42, {whole, level_row(source, 2)}));
  }
  const CellDb db(dir / "cells.db", CellDb::Mode::read_only);
  for (const bool blobs : {true, false}) {
    const auto row = db.get_cell(42, blobs);
    ASSERT_TRUE(row);
    ASSERT_EQ(row->far_geometry.size(), 2u);
    EXPECT_EQ(row->far_geometry[0].chunk_id, 3);
    EXPECT_EQ(row->far_geometry[0].level, 0);
    EXPECT_EQ(row->far_geometry[1].chunk_id, kChunk);
    EXPECT_EQ(row->far_geometry[1].level, 2);
    EXPECT_EQ(row->far_geometry[1].triangles, 1u);
    EXPECT_TRUE(row->far_geometry[1].whole);
  }
  EXPECT_EQ(check_cell(db, 42), "");
}

TEST(FarGeometryLevels, DecodesToAPieceDrawingTheLevelsChunk) {
  test::TempDir dir;
  const SourceWithLevels source;
  {
    CellDb db(dir / "cells.db", CellDb::Mode::read_write);
    db.put_cell(cell_with(42, {level_row(source, 1)}));
  }
  const CellDb db(dir / "cells.db", CellDb::Mode::read_only);
  const CellRow row = *db.get_cell(42);
  CellCheckContext with_source;
  with_source.store = &source;
  EXPECT_EQ(check_cell(db, 42, with_source), "");

  const DecodedCell cell = decode_cell(row, &source);
  EXPECT_TRUE(cell.far_whole_ids.empty());
  EXPECT_EQ(cell.far_geometry_triangles, 2u);
  ASSERT_EQ(cell.far_pieces.size(), 1u);
  const DecodedFarPiece& piece = cell.far_pieces[0];
  EXPECT_EQ(piece.level, 1);
  EXPECT_EQ(piece.chunk_id, kChunk);
  EXPECT_EQ(piece.cache_id, lod_cache_id(kChunk, 1));
  ASSERT_TRUE(piece.chunk);
  const auto level = source.load_lod(kChunk, 1);
  EXPECT_EQ(piece.chunk->id, piece.cache_id);
  EXPECT_EQ(piece.chunk->triangle_count(), 2u);
  EXPECT_EQ(piece.chunk->positions, level->positions);
  EXPECT_EQ(piece.chunk->colors, level->colors);
  EXPECT_EQ(piece.bounds, level->bounds);

  // Without a source the level is loaded when drawn, under the same cache id.
  const DecodedCell later = decode_cell(row);
  ASSERT_EQ(later.far_pieces.size(), 1u);
  EXPECT_FALSE(later.far_pieces[0].chunk);
  EXPECT_EQ(later.far_pieces[0].cache_id, piece.cache_id);
  const std::uint64_t loads = source.lod_load_count();
  const auto drawn = far_piece_chunk(later.far_pieces[0], source);
  EXPECT_EQ(source.lod_load_count(), loads + 1);
  EXPECT_EQ(drawn->id, piece.cache_id);
  EXPECT_EQ(drawn->positions, level->positions);
}

// `what` throws a std::runtime_error whose message holds every one of `parts`.
template <typename F>
void expect_error_naming(F what, const std::vector<std::string>& parts) {
  try {
    what();
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    for (const std::string& p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

TEST(FarGeometryLevels, AMissingLevelOrAWrongTriangleCountIsALocatedError) {
  test::TempDir dir;
  const SourceWithLevels source;
  FarGeometryRow missing = level_row(source, 1);
  missing.level = 3;  // the source lists levels 1 and 2
  FarGeometryRow miscounted = level_row(source, 2);
  miscounted.triangles = 7;
  {
    CellDb db(dir / "cells.db", CellDb::Mode::read_write);
    db.put_cell(cell_with(1, {missing}));
    db.put_cell(cell_with(2, {miscounted}));
  }
  const CellDb db(dir / "cells.db", CellDb::Mode::read_only);
  expect_error_naming([&] { decode_cell(*db.get_cell(1), &source); },
                      {"cell 1", "chunk 5", "level 3", "no such level"});
  expect_error_naming([&] { decode_cell(*db.get_cell(2), &source); },
                      {"cell 2", "chunk 5", "level 2", "7 triangles", "has 1"});
  // Without a source decoding defers to drawing, which names chunk and level too.
  const DecodedCell deferred = decode_cell(*db.get_cell(1));
  ASSERT_EQ(deferred.far_pieces.size(), 1u);
  expect_error_naming([&] { far_piece_chunk(deferred.far_pieces[0], source); }, {"chunk 5", "level 3"});

  // status --check / merge: sound on their own, refused against the source.
  EXPECT_EQ(check_cell(db, 1), "");
  CellCheckContext with_source;
  with_source.store = &source;
  const std::vector<CellProblem> problems = check_cells(db, with_source);
  ASSERT_EQ(problems.size(), 2u);
  EXPECT_EQ(problems[0].id, 1);
  EXPECT_NE(problems[0].reason.find("chunk 5 level 3: the store holds no such level"), std::string::npos)
      << problems[0].reason;
  EXPECT_EQ(problems[1].id, 2);
  EXPECT_NE(problems[1].reason.find("chunk 5 level 2: 7 triangles recorded, the store's level has 1"),
            std::string::npos)
      << problems[1].reason;
}

TEST(FarGeometryLevels, DamagedLevelsAreFoundWithoutASource) {
  test::TempDir dir;
  const SourceWithLevels source;
  FarGeometryRow negative = level_row(source, 1), partial = level_row(source, 1), blob = level_row(source, 1),
                 too_high = level_row(source, 1);
  negative.level = -1;
  partial.whole = false;
  blob.geometry = {1, 2, 3};
  blob.whole = true;
  too_high.level = kMaxFarGeometryLevel + 1;
  {
    CellDb db(dir / "cells.db", CellDb::Mode::read_write);
    db.put_cell(cell_with(1, {negative}));
    db.put_cell(cell_with(2, {partial}));
    db.put_cell(cell_with(3, {blob}));
    db.put_cell(cell_with(4, {too_high}));
  }
  const CellDb db(dir / "cells.db", CellDb::Mode::read_only);
  const std::vector<std::pair<std::int64_t, std::string>> expected = {
      {1, "chunk 5 level -1: a level is never negative"},
      {2, "chunk 5 level 1: a level row not marked whole"},
      {3, "chunk 5 level 1: a level row with a geometry blob"},
      {4, "chunk 5 level 16: past the highest level"}};
  for (const auto& [id, text] : expected) {
    EXPECT_NE(check_cell(db, id).find(text), std::string::npos) << id << ": " << check_cell(db, id);
    expect_error_naming([&, id = id] { decode_cell(*db.get_cell(id)); },
                        {"cell " + std::to_string(id), text});
  }
}

TEST(FarGeometryLevels, TheSameChunkLevelInTwoCellsSharesOneCacheId) {
  const SourceWithLevels source;
  FarGeometryRow cut;  // seen triangles of another chunk: a piece of each cell's own
  cut.chunk_id = kChunk + 1;
  cut.triangles = 1;
  cut.bounds = source.load(kChunk)->bounds;
  cut.geometry = encode_triangle_list(std::vector<std::uint32_t>{0});
  const DecodedCell one = decode_cell(cell_with(1, {level_row(source, 1), cut}));
  const DecodedCell two = decode_cell(cell_with(2, {level_row(source, 1), cut}));
  const DecodedCell coarser = decode_cell(cell_with(3, {level_row(source, 2)}));
  ASSERT_EQ(one.far_pieces.size(), 2u);
  ASSERT_EQ(two.far_pieces.size(), 2u);
  ASSERT_EQ(coarser.far_pieces.size(), 1u);
  EXPECT_EQ(one.far_pieces[0].cache_id, two.far_pieces[0].cache_id);
  EXPECT_NE(one.far_pieces[1].cache_id, two.far_pieces[1].cache_id);
  EXPECT_LT(one.far_pieces[1].cache_id, 0);
  EXPECT_NE(one.far_pieces[0].cache_id, coarser.far_pieces[0].cache_id);
  EXPECT_EQ(one.far_pieces[0].cache_id, (std::int64_t{1} << 62) + kChunk * 16 + 1);
  // Apart from the store's chunk ids and per-cell pieces (negative).
  EXPECT_GT(lod_cache_id(1, 1), std::int64_t{1} << 62);
  EXPECT_NE(lod_cache_id(1, 2), lod_cache_id(2, 1));
  EXPECT_EQ(lod_cache_id((std::int64_t{1} << 58) - 1, kMaxFarGeometryLevel),
            std::numeric_limits<std::int64_t>::max());
  EXPECT_THROW(lod_cache_id(kChunk, 0), std::invalid_argument);
  EXPECT_THROW(lod_cache_id(kChunk, kMaxFarGeometryLevel + 1), std::invalid_argument);
  EXPECT_THROW(lod_cache_id(0, 1), std::invalid_argument);
  EXPECT_THROW(lod_cache_id(std::int64_t{1} << 58, 1), std::invalid_argument);
}

// Two cells drawing level 1 of chunk 5, decoded without a source: the drawer
// loads the level (green, not the chunk's red) once, for both cells.
TEST(FarGeometryLevels, TwoCellsDrawTheLevelFromOneCacheEntry) {
  const SourceWithLevels source;
  const DecodedCell one = decode_cell(cell_with(1, {level_row(source, 1)}));
  const DecodedCell two = decode_cell(cell_with(2, {level_row(source, 1)}));
  const std::uint64_t chunk_loads = source.load_count();  // level_row's, for the bounds
  SceneDrawer drawer(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), source);
  SceneDrawOptions options;
  options.near_field = false;
  const RenderCamera camera = test::camera_down({101, 1, 10}, 0.05);  // sees the middle 1 x 1 of the square
  ViewFrame frame;
  const SceneFrameStats first = drawer.draw_impostor(camera, 16, 16, one, options, frame);
  EXPECT_EQ(first.far_geometry_triangles, 2u);
  for (std::size_t i = 0; i < frame.color.size(); ++i) {
    ASSERT_TRUE(frame.covered(i)) << i;
    EXPECT_GT(frame.color[i].g, 4 * frame.color[i].r) << i;  // the level's colour
  }
  const std::uint64_t uploads = drawer.chunk_stats().uploads, loads = source.lod_load_count();
  const SceneFrameStats second = drawer.draw_impostor(camera, 16, 16, two, options, frame);
  EXPECT_EQ(second.far_geometry_triangles, 2u);
  EXPECT_EQ(drawer.chunk_stats().uploads, uploads);  // the first cell's upload drawn again
  EXPECT_EQ(source.lod_load_count(), loads);
  EXPECT_EQ(source.load_count(), chunk_loads);  // the chunk itself never loaded for drawing
}

// `verify --lod-cut`'s yardstick: chunk 5 seen from 10 m above with 1/16 of
// 1 m a pixel (0.0625 m): level 1 (0.01 m, 0.16 px) and level 2 (0.5 m, 8 px).
TEST(FarGeometryLevels, TheLodCutDrawsEachChunkAtTheLevelItsPixelErrorAllows) {
  const SourceWithLevels source;
  SceneDrawer drawer(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), source);
  const RenderCamera camera = test::camera_down({101, 1, 10}, 0.05);
  SceneDrawOptions options;
  ViewFrame truth, frame;
  drawer.draw_truth(camera, 16, 16, options, truth);
  LodCut cut;
  const auto centre_colour = [&] { return frame.color[8 * 16 + 8]; };
  drawer.draw_lod_cut(camera, 16, 16, options, 0, 0.1, frame, &cut);  // exact: the truth itself
  EXPECT_EQ(cut.levels, std::vector<int>{0});
  EXPECT_EQ(cut.triangles, 4u);
  EXPECT_TRUE(std::isinf(compare_frames(frame, truth).psnr_db));
  const SceneFrameStats green = drawer.draw_lod_cut(camera, 16, 16, options, 0, 1.0, frame, &cut);
  EXPECT_EQ(cut.levels, std::vector<int>{1});
  EXPECT_EQ(green.chunk_triangles, 2u);
  EXPECT_GT(centre_colour().g, 4 * centre_colour().r);
  drawer.draw_lod_cut(camera, 16, 16, options, 0, 10.0, frame, &cut);
  EXPECT_EQ(cut.levels, std::vector<int>{2});
  EXPECT_EQ(cut.triangles, 1u);
  // By triangles: the finest cut that fits.
  for (const auto& [budget, level] : std::vector<std::pair<std::uint64_t, int>>{{4, 0}, {3, 1}, {2, 1}, {1, 2}}) {
    drawer.draw_lod_cut(camera, 16, 16, options, budget, 0, frame, &cut);
    EXPECT_EQ(cut.levels, std::vector<int>{level}) << budget << " triangles";
  }
}

TEST(FarGeometryLevels, MergeCarriesTheLevel) {
  test::TempDir dir;
  const SourceWithLevels source;
  {
    CellDb shard(dir / "shard.db", CellDb::Mode::read_write);
    shard.put_cell(cell_with(9, {level_row(source, 2)}));
  }
  CellDb merged(dir / "merged.db", CellDb::Mode::read_write);
  const CellDb shard(dir / "shard.db", CellDb::Mode::read_only);
  CellCheckContext with_source;
  with_source.store = &source;
  EXPECT_EQ(copy_cells(merged, shard, with_source).copied, 1u);
  const auto row = merged.get_cell(9);
  ASSERT_TRUE(row);
  ASSERT_EQ(row->far_geometry.size(), 1u);
  EXPECT_EQ(row->far_geometry[0].level, 2);
  EXPECT_EQ(check_cell(merged, 9, with_source), "");
}

}  // namespace
}  // namespace cellbake
