// Bake configuration: parsing, unknown keys and bad values named by file and
// line, --set overrides, cell enumeration and selection.
#include <gtest/gtest.h>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/embedded_configs.h"
#include "test_support.h"

namespace cellbake {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(BakeConfig, ParsesEveryKeyAndResolvesPathsAgainstTheFile) {
  test::TempDir dir;
  test::write_text(dir / "c.toml", R"(
[model]
store = "s.db"
up = "y"
[[regions]]
min = [0, 0, 0]
max = [10, 2, 4]
[cells]
size = 2
[near]
budget = 5000
[sample]
face_size = 64
supersample = 2
[simplify]
max_triangles = 500
[encode]
image_format = "png"
[output]
database = "out/cells.db"
)");
  BakeConfig c = load_bake_config(dir / "c.toml");
  EXPECT_EQ(c.store, dir / "s.db");
  EXPECT_EQ(c.database, dir / "out/cells.db");
  EXPECT_EQ(c.up, "y");
  ASSERT_EQ(c.regions.size(), 1u);
  EXPECT_EQ(c.regions[0].hi.x, 10);
  EXPECT_EQ(c.near_budget, 5000u);
  EXPECT_EQ(c.face_size, 64);
  EXPECT_EQ(c.supersample, 2);
  EXPECT_EQ(c.max_face_triangles, 500);
  EXPECT_EQ(c.image_format, "png");
  EXPECT_NO_THROW(validate_bake_config(c));
}

TEST(BakeConfig, UnknownKeysAndBadValuesNameFileAndLine) {
  test::TempDir dir;
  test::write_text(dir / "a.toml", "[cells]\nsize = 2\n[near]\nbudgte = 5\n");
  std::string e = error_of([&] { load_bake_config(dir / "a.toml"); });
  EXPECT_NE(e.find("a.toml:4"), std::string::npos) << e;
  EXPECT_NE(e.find("near.budgte"), std::string::npos) << e;

  test::write_text(dir / "b.toml", "[sample]\n\nface_size = 5\n");
  e = error_of([&] { load_bake_config(dir / "b.toml"); });
  EXPECT_NE(e.find("b.toml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;

  test::write_text(dir / "c.toml", "[encode]\nimage_format = \"gif\"\n");
  e = error_of([&] { load_bake_config(dir / "c.toml"); });
  EXPECT_NE(e.find("c.toml:2"), std::string::npos) << e;

  test::write_text(dir / "d.toml", "[[regions]]\nmin = [0, 0]\nmax = [1, 1, 1]\n");
  e = error_of([&] { load_bake_config(dir / "d.toml"); });
  EXPECT_NE(e.find("d.toml:2"), std::string::npos) << e;

  test::write_text(dir / "e.toml", "[cells\nsize = 2\n");
  e = error_of([&] { load_bake_config(dir / "e.toml"); });
  EXPECT_NE(e.find("e.toml:1"), std::string::npos) << e;

  test::write_text(dir / "f.toml", "[near]\nbudget = 1.5\n");
  e = error_of([&] { load_bake_config(dir / "f.toml"); });
  EXPECT_NE(e.find("integer"), std::string::npos) << e;
}

TEST(BakeConfig, OverridesValidateLikeFileKeys) {
  BakeConfig c;
  apply_override(c, "near.budget=123");
  apply_override(c, "encode.image_format=webp");
  apply_override(c, "encode.image_format=\"png\"");
  EXPECT_EQ(c.near_budget, 123u);
  EXPECT_EQ(c.image_format, "png");
  EXPECT_NE(error_of([&] { apply_override(c, "near.nope=1"); }).find("unknown key"), std::string::npos);
  EXPECT_NE(error_of([&] { apply_override(c, "sample.face_size=0"); }).find("out of range"), std::string::npos);
  EXPECT_NE(error_of([&] { apply_override(c, "novalue"); }).find("section.key=value"), std::string::npos);
}

TEST(BakeConfig, ValidationRequiresStoreAndRegions) {
  BakeConfig c;
  EXPECT_THROW(validate_bake_config(c), std::runtime_error);
  c.store = "x.db";
  EXPECT_THROW(validate_bake_config(c), std::runtime_error);
  c.regions.push_back({{0, 0, 0}, {1, 1, 1}});
  EXPECT_NO_THROW(validate_bake_config(c));
}

TEST(BakeConfig, EmbeddedDemoConfigParses) {
  BakeConfig c = parse_bake_config(embedded_plant_demo_config(), "/tmp/demo/plant-demo.toml");
  EXPECT_EQ(c.store, std::filesystem::path("/tmp/demo/plant.store.db"));
  EXPECT_GE(enumerate_cells(c.regions, c.cell_size).size(), 50u);
}

TEST(CellGrid, TilesRegionsFromTheMinimumCorner) {
  auto cells = enumerate_cells({Box3d{{0, 0, 1.7}, {10, 4, 1.7}}}, 2.0);
  ASSERT_EQ(cells.size(), 10u);  // 5 x 2 x 1 (a flat region gives one layer)
  EXPECT_EQ(cells[0].id, 1);
  EXPECT_EQ(cells[0].bounds.lo.x, 0);
  EXPECT_EQ(cells[0].bounds.hi.x, 2);
  EXPECT_DOUBLE_EQ(cells[0].center().z, 1.7);
  EXPECT_EQ(cells[9].gx, 4);
  EXPECT_EQ(cells[9].gy, 1);
  auto two = enumerate_cells({Box3d{{0, 0, 0}, {2, 2, 2}}, Box3d{{10, 10, 10}, {13, 12, 12}}}, 2.0);
  ASSERT_EQ(two.size(), 3u);  // 1 + 2 x 1 x 1 (3 m is two cells)
  EXPECT_EQ(two[1].region, 1);
  EXPECT_THROW(enumerate_cells({Box3d{{0, 0, 0}, {1e6, 1e6, 1e6}}}, 0.01), std::invalid_argument);
  EXPECT_THROW(enumerate_cells({Box3d{{0, 0, 0}, {1, 1, 1}}}, 0), std::invalid_argument);
}

TEST(CellGrid, SelectsCellsByIdRanges) {
  auto cells = enumerate_cells({Box3d{{0, 0, 0}, {20, 2, 2}}}, 2.0);
  auto sel = select_cells(cells, "1-3,5,9-");
  std::vector<std::int64_t> ids;
  for (const auto& c : sel) ids.push_back(c.id);
  EXPECT_EQ(ids, (std::vector<std::int64_t>{1, 2, 3, 5, 9, 10}));
  EXPECT_THROW(select_cells(cells, "3-1"), std::invalid_argument);
  EXPECT_THROW(select_cells(cells, "a"), std::invalid_argument);
  EXPECT_THROW(select_cells(cells, "1,,2"), std::invalid_argument);
}

}  // namespace
}  // namespace cellbake
