// Bake configuration: parsing, unknown keys and bad values named by file and
// line, --set overrides, cell enumeration and selection.
#include <gtest/gtest.h>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"
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

TEST(BakeConfig, ShadingKeysParseValidateAndEnterTheSampleHash) {
  test::TempDir dir;
  test::write_text(dir / "s.toml", R"(
[shading]
mode = "lit"
key_direction = [0, 1, 2]
key_strength = 0.7
fill_direction = [1, 0, 0]
fill_strength = 0.2
ambient = 0.25
)");
  const BakeConfig c = load_bake_config(dir / "s.toml");
  EXPECT_EQ(c.shading.mode, ShadingMode::lit);
  EXPECT_EQ(c.shading.key_direction, (Vec3d{0, 1, 2}));
  EXPECT_EQ(c.shading.key_strength, 0.7);
  EXPECT_EQ(c.shading.fill_direction, (Vec3d{1, 0, 0}));
  EXPECT_EQ(c.shading.fill_strength, 0.2);
  EXPECT_EQ(c.shading.ambient, 0.25);
  const std::string text = describe_bake_config(c);
  EXPECT_NE(text.find("shading.mode=lit\n"), std::string::npos) << text;
  EXPECT_NE(text.find("shading.key_direction=0,1,2\n"), std::string::npos) << text;

  test::write_text(dir / "zero.toml", "[shading]\n\nkey_direction = [0, 0, 0]\n");
  std::string e = error_of([&] { load_bake_config(dir / "zero.toml"); });
  EXPECT_NE(e.find("zero.toml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("zero vector"), std::string::npos) << e;
  test::write_text(dir / "mode.toml", "[shading]\nmode = \"phong\"\n");
  e = error_of([&] { load_bake_config(dir / "mode.toml"); });
  EXPECT_NE(e.find("mode.toml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("lit, unlit"), std::string::npos) << e;
  BakeConfig o;
  EXPECT_NE(error_of([&] { apply_override(o, "shading.ambient=-1"); }).find("out of range"), std::string::npos);
  EXPECT_NE(error_of([&] { apply_override(o, "shading.fill_direction=[1, 2]"); }).find("3 numbers"), std::string::npos);
  apply_override(o, "shading.mode=unlit");
  EXPECT_EQ(o.shading.mode, ShadingMode::unlit);

  // Shading is part of the sample stage's hash, not the cull box's.
  BakeConfig a;
  a.regions = {Box3d{{0, 0, 0}, {2, 2, 2}}};
  const CellSpec cell = enumerate_cells(a.regions, a.cell_size).front();
  const CellHashes base = cell_hashes(cell, a, "store");
  for (const char* change : {"shading.mode=unlit", "shading.key_strength=0.5", "shading.fill_direction=[0,1,0]",
                             "shading.ambient=0.2", "shading.key_direction=[1,1,1]", "shading.fill_strength=0.1"}) {
    BakeConfig b = a;
    apply_override(b, change);
    const CellHashes h = cell_hashes(cell, b, "store");
    EXPECT_EQ(h.cull, base.cull) << change;
    EXPECT_NE(h.input, base.input) << change;
  }
}

TEST(BakeConfig, EncodeCodecKeysSelectTheCodecsAndEnterTheInputHash) {
  BakeConfig a;
  EXPECT_EQ(a.image_format, "avif") << "the measured best (issue #16)";
  EXPECT_EQ(a.mesh_codec, "grid");
  a.regions = {Box3d{{0, 0, 0}, {2, 2, 2}}};
  const CellSpec cell = enumerate_cells(a.regions, a.cell_size).front();
  const CellHashes base = cell_hashes(cell, a, "store");
  for (const char* change : {"encode.image_format=jxl", "encode.image_format=jpeg", "encode.quality=70",
                             "encode.mesh_codec=quantized", "encode.mesh_depth_error=0.0005"}) {
    BakeConfig b = a;
    apply_override(b, change);
    const CellHashes h = cell_hashes(cell, b, "store");
    EXPECT_EQ(h.cull, base.cull) << change;
    EXPECT_NE(h.input, base.input) << change;
    const std::string key = std::string(change).substr(0, std::string(change).find('='));
    EXPECT_NE(describe_bake_config(b).find(key + "="), std::string::npos) << change;
  }
  BakeConfig c;
  apply_override(c, "encode.image_format=jxl");
  apply_override(c, "encode.mesh_codec=quantized");
  apply_override(c, "encode.mesh_depth_error=0.002");
  EXPECT_EQ(c.image_format, "jxl");
  EXPECT_EQ(c.mesh_codec, "quantized");
  EXPECT_DOUBLE_EQ(c.mesh_depth_error, 0.002);
  EXPECT_NE(error_of([&] { apply_override(c, "encode.image_format=heic"); }), "");
  EXPECT_NE(error_of([&] { apply_override(c, "encode.mesh_codec=draco"); }), "");
  EXPECT_NE(error_of([&] { apply_override(c, "encode.mesh_depth_error=0"); }).find("out of range"), std::string::npos);
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
