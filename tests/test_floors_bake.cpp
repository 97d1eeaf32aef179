// Whole floors as one job (issue #36, "What to build" 2): `bake --floors` and
// `[cells] floors` turn the floors `cellbake info` finds into regions before
// cell ids are given, so a floors bake equals the --region bake it stands for
// (cell ids, input and content hashes), also through Slurm shards and a
// resume; an unknown floor is an error naming the floors found. `--dry-run
// --measure K` bakes K stratified cells into a temporary database that is
// removed (also on failure and Ctrl-C) and projects the whole bake. The
// arithmetic (floor regions, stratified choice, projection) is checked
// analytically; the command on a generated 100 k-triangle house (floors at
// z = 0 and 3, a roof) with 32² faces and one sample per cell.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "pipeline/bake_config.h"
#include "pipeline/bake_projection.h"
#include "pipeline/floor_regions.h"
#include "pipeline/ingest.h"
#include "pipeline/stratified_cells.h"
#include "runner/measured_estimate.h"
#include "runner/parallel.h"
#include "storage/cell_db.h"
#include "tests/fixture_house_model.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::run_cellbake;
using test::TempDir;

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

nlohmann::json json_of(const test::CommandResult& r) {
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto brace = r.output.find('{');
  if (brace == std::string::npos) {
    ADD_FAILURE() << r.output;
    return {};
  }
  return nlohmann::json::parse(r.output.substr(brace));
}

// ---------------------------------------------------------------- selection

TEST(FloorSelection, ParsesAllNoneAndIndices) {
  EXPECT_TRUE(parse_floor_selection("all", "--floors").all);
  EXPECT_TRUE(parse_floor_selection("none", "--floors").empty());
  const FloorSelection s = parse_floor_selection("2, 0,2", "--floors");
  EXPECT_FALSE(s.all);
  EXPECT_EQ(s.indices, (std::vector<int>{0, 2}));
  EXPECT_EQ(floor_selection_text(s), "0,2");
  for (const char* bad : {"", "x", "-1", "1,,2", "1.5", "all,1"}) {
    try {
      parse_floor_selection(bad, "--floors");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("--floors"), std::string::npos) << e.what();
    }
  }
}

TEST(FloorSelection, ConfigKeyTakesAllOrAnArrayAndNeedsNoRegions) {
  const BakeConfig all = parse_bake_config("[model]\nstore = \"s.db\"\n[cells]\nfloors = \"all\"\n", "/x/c.toml");
  EXPECT_TRUE(all.floors.all);
  EXPECT_NO_THROW(validate_bake_config(all));  // floors stand in for regions
  const BakeConfig some =
      parse_bake_config("[model]\nstore = \"s.db\"\n[cells]\nfloors = [2, 0]\neye_height = 1.6\n", "/x/c.toml");
  EXPECT_EQ(some.floors.indices, (std::vector<int>{0, 2}));
  EXPECT_DOUBLE_EQ(some.eye_height, 1.6);
  for (const char* bad : {"floors = 3", "floors = [-1]", "floors = []", "floors = \"most\"", "floors = [1.5]"}) {
    try {
      parse_bake_config(std::string("[cells]\n") + bad + "\n", "/x/c.toml");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("c.toml:2"), std::string::npos) << e.what();
    }
  }
  BakeConfig none;
  none.store = "s.db";
  EXPECT_THROW(validate_bake_config(none), std::runtime_error);
  apply_override(none, "cells.floors=0,1");
  EXPECT_EQ(none.floors.indices, (std::vector<int>{0, 1}));
  apply_override(none, "cells.floors=[1]");
  EXPECT_EQ(none.floors.indices, (std::vector<int>{1}));
}

// ---------------------------------------------------------------- regions

TEST(FloorRegions, EyeHeightIsRoundedAsInfoPrintsIt) {
  EXPECT_EQ(rounded_as_info_prints(0.0049 + 1.7, 2.0), std::strtod("1.70", nullptr));
  EXPECT_EQ(rounded_as_info_prints(1.23456, 1.0), std::strtod("1.23", nullptr));
  EXPECT_EQ(rounded_as_info_prints(1.23456, 0.5), std::strtod("1.235", nullptr));  // finer under a cell of 1
  EXPECT_EQ(rounded_as_info_prints(-2.3051, 4.0), std::strtod("-2.31", nullptr));
}

TEST(FloorRegions, EachSelectedFloorIsALayerAtEyeHeightOverEachFootprint) {
  const std::vector<double> heights{0.0, 3.0, 6.0};
  const Box3d bounds{{0, 0, 0}, {10, 8, 6.5}};
  const std::vector<Box3d> footprints{Box3d{{1, 1, 0}, {5, 7, 9}}, Box3d{{6, 1, 2}, {9, 7, 2}}};
  FloorSelection all;
  all.all = true;
  // Cell 1: the roof's eyes (7.7) are more than a cell above the top (6.5): "all" leaves it out, with a note.
  const FloorRegions r = floor_regions(heights, all, footprints, 2, 1.7, bounds, 1.0);
  EXPECT_EQ(r.heights, heights);
  ASSERT_EQ(r.regions.size(), 4u);  // floors 0 and 1, footprint by footprint
  const double eyes[] = {1.7, 1.7, 4.7, 4.7};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(r.regions[i].floor, int(i / 2));
    EXPECT_EQ(r.regions[i].eye, eyes[i]);
    const Box3d& fp = footprints[i % 2];
    EXPECT_EQ(r.regions[i].region.lo, (Vec3d{fp.lo.x, fp.lo.y, eyes[i]}));
    EXPECT_EQ(r.regions[i].region.hi, (Vec3d{fp.hi.x, fp.hi.y, eyes[i]}));
  }
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("floor 2"), std::string::npos) << r.notes[0];
  // Cell 2 reaches 8.5: the roof stays. Named by index, it stays whatever the cell.
  EXPECT_EQ(floor_regions(heights, all, {bounds}, 2, 1.7, bounds, 2.0).regions.size(), 3u);
  const FloorRegions roof = floor_regions(heights, parse_floor_selection("2", "t"), {bounds}, 2, 1.7, bounds, 1.0);
  ASSERT_EQ(roof.regions.size(), 1u);
  EXPECT_EQ(roof.regions[0].eye, 7.7);
  EXPECT_TRUE(roof.notes.empty());
}

TEST(FloorRegions, YUpReplacesTheYExtent) {
  const Box3d bounds{{0, -1, 0}, {10, 5, 8}};
  const FloorRegions r = floor_regions({-1.0, 2.5}, parse_floor_selection("1", "t"), {bounds}, 1, 1.5, bounds, 2.0);
  ASSERT_EQ(r.regions.size(), 1u);
  EXPECT_EQ(r.regions[0].region.lo, (Vec3d{0, 4, 0}));
  EXPECT_EQ(r.regions[0].region.hi, (Vec3d{10, 4, 8}));
}

TEST(FloorRegions, AnUnknownFloorNamesTheFloorsFound) {
  const Box3d bounds{{0, 0, 0}, {10, 8, 6.5}};
  try {
    floor_regions({0.0, 3.0}, parse_floor_selection("0,5", "t"), {bounds}, 2, 1.7, bounds, 1.0);
    ADD_FAILURE() << "floor 5 accepted";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("floor 5"), std::string::npos) << m;
    EXPECT_NE(m.find("2 floors: 0 at z = 0, 1 at z = 3"), std::string::npos) << m;
  }
  FloorSelection all;
  all.all = true;
  EXPECT_THROW(floor_regions({}, all, {bounds}, 2, 1.7, bounds, 1.0), std::runtime_error);  // none found
}

// ---------------------------------------------------------------- stratified choice

TEST(StratifiedCells, SharesFollowTheStrataSizes) {
  EXPECT_EQ(stratum_shares({100, 50, 50}, 8), (std::vector<std::size_t>{4, 2, 2}));
  EXPECT_EQ(stratum_shares({10, 0, 5}, 3), (std::vector<std::size_t>{2, 0, 1}));
  EXPECT_EQ(stratum_shares({1, 90, 9}, 10), (std::vector<std::size_t>{1, 8, 1}));  // at least one each
  EXPECT_EQ(stratum_shares({5, 5, 5, 5}, 2), (std::vector<std::size_t>{0, 1, 0, 1}));  // fewer picks than strata
  EXPECT_EQ(stratum_shares({2, 3}, 9), (std::vector<std::size_t>{2, 3}));             // more picks than cells
}

TEST(StratifiedCells, PicksSpreadOverTheGridAndTheRegions) {
  // One 8 x 8 layer: four picks, one in each 4 x 4 quadrant.
  const std::vector<CellSpec> grid = enumerate_cells({Box3d{{0, 0, 1}, {8, 8, 1}}}, 1.0);
  ASSERT_EQ(grid.size(), 64u);
  const std::vector<CellSpec> four = stratified_cells(grid, 4);
  ASSERT_EQ(four.size(), 4u);
  int quadrants[4] = {0, 0, 0, 0};
  for (const CellSpec& c : four) ++quadrants[(c.gx / 4) + 2 * (c.gy / 4)];
  for (int n : quadrants) EXPECT_EQ(n, 1);
  for (std::size_t i = 1; i < four.size(); ++i) EXPECT_LT(four[i - 1].id, four[i].id);
  // Two floors of 64 and 16 cells: 5 picks go 4 and 1.
  const std::vector<CellSpec> floors =
      enumerate_cells({Box3d{{0, 0, 1}, {8, 8, 1}}, Box3d{{0, 0, 4}, {4, 4, 4}}}, 1.0);
  int per_region[2] = {0, 0};
  for (const CellSpec& c : stratified_cells(floors, 5)) ++per_region[c.region];
  EXPECT_EQ(per_region[0], 4);
  EXPECT_EQ(per_region[1], 1);
  EXPECT_EQ(stratified_cells(floors, 1000).size(), floors.size());
}

// ---------------------------------------------------------------- projection

TEST(BakeProjection, WallTimeIsTheBusiestThreadsCells) {
  // 4 cells measured at 40 CPU-s and 400 kB: 10 s and 100 kB a cell.
  const BakeProjection p = project_bake({4, 40.0, 400e3}, 101, 2, {10, 3, 200}, 4);
  EXPECT_DOUBLE_EQ(p.cpu_seconds_per_cell, 10.0);
  EXPECT_DOUBLE_EQ(p.bytes_per_cell, 100e3);
  EXPECT_DOUBLE_EQ(p.cpu_seconds, 1010.0);
  EXPECT_DOUBLE_EQ(p.bytes, 10.1e6);
  EXPECT_DOUBLE_EQ(p.wall_seconds, 51 * 10.0);  // ceil(101 / 2) cells on the busiest thread
  ASSERT_EQ(p.shards.size(), 3u);
  EXPECT_EQ(p.shards[0].cells_per_shard, 11u);  // ceil(101 / 10)
  EXPECT_DOUBLE_EQ(p.shards[0].wall_seconds, 3 * 10.0);  // ceil(11 / 4)
  EXPECT_EQ(p.shards[1].cells_per_shard, 34u);
  EXPECT_DOUBLE_EQ(p.shards[1].wall_seconds, 9 * 10.0);
  EXPECT_EQ(p.shards[2].cells_per_shard, 1u);  // more shards than cells: one cell's time
  EXPECT_DOUBLE_EQ(p.shards[2].wall_seconds, 10.0);
  EXPECT_THROW(project_bake({0, 1, 1}, 10, 2, {}, 2), std::invalid_argument);
  EXPECT_THROW(project_bake({1, -1, 1}, 10, 2, {}, 2), std::invalid_argument);
  EXPECT_THROW(project_bake({1, 1, 1}, 10, 0, {}, 2), std::invalid_argument);
  EXPECT_THROW(project_bake({1, 1, 1}, 10, 2, {0}, 2), std::invalid_argument);
}

TEST(MeasuredEstimate, CellSelectionText) {
  EXPECT_EQ(cell_selection_text({1, 2, 3, 7, 9, 10}), "1-3,7,9-10");
  EXPECT_EQ(cell_selection_text({5}), "5");
}

// ---------------------------------------------------------------- the command on a house

// Cheap cells: 32² faces, one sample at the centre.
const char* kCheap = " --cell-size 2 --face-size 32 --set samples.initial=centre --set samples.max=1 --quiet";

class FloorsBake : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const auto r = run_cellbake("generate house --triangles 100000 --seed 1 --out " + q(*dir_ / "house.ply") +
                                " --store " + q(*dir_ / "house.store.db"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string store() { return q(*dir_ / "house.store.db"); }
  static std::string bake(const std::string& options) { return "bake --store " + store() + kCheap + " " + options; }
  static TempDir* dir_;
};
TempDir* FloorsBake::dir_ = nullptr;

std::string region_option(const nlohmann::json& r) {
  std::ostringstream o;
  o.precision(17);
  for (int i = 0; i < 6; ++i) o << (i ? "," : "") << r[i].get<double>();
  return o.str();
}

TEST_F(FloorsBake, FloorsBakeAsTheEquivalentRegionsAndShardsAndResumeAgree) {
  TempDir dir;
  // The floors info finds are the floors a floors bake uses.
  const auto info = json_of(run_cellbake("info --json " + store()));
  ASSERT_GE(info["floors"].size(), 2u) << info.dump();
  const auto plan = json_of(run_cellbake(bake("--floors 0,1 --dry-run --json")));
  ASSERT_EQ(plan["floors"]["found"].size(), info["floors"].size());
  const auto& selected = plan["floors"]["selected"];
  ASSERT_EQ(selected.size(), 2u);
  for (int f = 0; f < 2; ++f) {
    EXPECT_EQ(selected[f]["floor"], f);
    EXPECT_DOUBLE_EQ(selected[f]["height"].get<double>(), info["floors"][f]["height"].get<double>());
    EXPECT_NEAR(selected[f]["eye"].get<double>(), info["floors"][f]["height"].get<double>() + 1.7, 0.006);
  }
  ASSERT_EQ(plan["regions"].size(), 2u);
  const std::string regions =
      "--region " + region_option(plan["regions"][0]) + " --region " + region_option(plan["regions"][1]);
  // Two cells of floor 0 and the first of floor 1.
  const std::int64_t upstairs = selected[1]["first_id"];
  const std::string cells = " --cells 1-2," + std::to_string(upstairs);

  // Through --floors, through the --regions the dry run printed, and as two shards merged.
  const auto a = run_cellbake(bake("--floors 0,1" + cells + " --out " + q(dir / "floors.db")));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const auto b = run_cellbake(bake(regions + cells + " --out " + q(dir / "region.db")));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  for (const char* shard : {"0/2", "1/2"}) {
    const auto s = run_cellbake(bake("--floors 0,1" + cells + " --shard " + std::string(shard) + " --out " +
                                     q(dir / ("shard" + std::string(1, shard[0]) + ".db"))));
    ASSERT_EQ(s.exit_code, 0) << s.output;
  }
  const auto m = run_cellbake("merge " + q(dir / "merged.db") + " " + q(dir / "shard0.db") + " " +
                              q(dir / "shard1.db") + " --quiet");
  ASSERT_EQ(m.exit_code, 0) << m.output;

  const CellDb fa(dir / "floors.db", CellDb::Mode::read_only), fb(dir / "region.db", CellDb::Mode::read_only);
  EXPECT_EQ(fa.meta("config"), fb.meta("config"));
  const auto sa = fa.stamps(), sb = fb.stamps();
  ASSERT_EQ(sa.size(), 3u);
  ASSERT_EQ(sb.size(), 3u);
  for (const auto& [id, stamp] : sa) {
    ASSERT_TRUE(sb.count(id)) << id;
    EXPECT_EQ(stamp.status, "done");
    EXPECT_EQ(stamp.input_hash, sb.at(id).input_hash) << id;
    EXPECT_EQ(stamp.content_hash, sb.at(id).content_hash) << id;
    const auto ca = fa.get_cell(id, false), cb = fb.get_cell(id, false);
    EXPECT_EQ(ca->bounds, cb->bounds) << id;
    EXPECT_EQ(ca->region, cb->region) << id;
    EXPECT_EQ(ca->region, id == upstairs ? 1 : 0) << id;
    EXPECT_NEAR(ca->bounds.center().z, selected[ca->region]["eye"].get<double>(), 1e-9) << id;
  }
  const std::string hash = fa.totals().content_hash;
  EXPECT_EQ(hash, fb.totals().content_hash);
  EXPECT_EQ(hash, CellDb(dir / "merged.db", CellDb::Mode::read_only).totals().content_hash);

  // A rerun resumes: every cell up to date.
  const auto again = json_of(run_cellbake(bake("--floors 0,1" + cells + " --json --out " + q(dir / "floors.db"))));
  EXPECT_EQ(again["cells_up_to_date"], 3);
  EXPECT_EQ(again["cells_baked"], 0);
}

TEST_F(FloorsBake, AllFloorsAndTheErrors) {
  const auto info = json_of(run_cellbake("info --json " + store()));
  const std::size_t found = info["floors"].size();
  const auto all = json_of(run_cellbake(bake("--floors all --dry-run --json")));
  const auto& floors = all["floors"];
  // Every floor found is either a region or left out with a note; cells count up region by region.
  EXPECT_EQ(floors["selected"].size() + floors["notes"].size(), found) << floors.dump();
  ASSERT_EQ(floors["selected"].size(), all["regions"].size());
  std::int64_t next = 1;
  for (const auto& f : floors["selected"]) {
    EXPECT_EQ(f["first_id"].get<std::int64_t>(), next);
    next = f["last_id"].get<std::int64_t>() + 1;
  }
  EXPECT_EQ(all["cells_total"].get<std::int64_t>(), next - 1);
  // Without regions a floor's footprint is where people walk on it: the main
  // floor's region is the one info suggests (rounded as info prints it).
  const auto& suggested = info["suggested"];
  ASSERT_TRUE(suggested.is_object()) << info.dump();
  bool main_floor_seen = false;
  for (std::size_t i = 0; i < floors["selected"].size(); ++i) {
    const int f = floors["selected"][i]["floor"];
    if (info["floors"][f]["height"] != suggested["floor"]) continue;
    main_floor_seen = true;
    for (int k : {0, 1, 3, 4})
      EXPECT_NEAR(all["regions"][i][k].get<double>(), suggested["region"][k].get<double>(), 0.0051) << k;
  }
  EXPECT_TRUE(main_floor_seen) << all.dump();
  // The same from a configuration file, and with --cells.
  TempDir dir;
  test::write_text(dir / "floors.toml", "[model]\nstore = " + nlohmann::json((*dir_ / "house.store.db").string()).dump() +
                                            "\n[cells]\nfloors = \"all\"\nsize = 2\n");
  const auto config = json_of(run_cellbake("bake " + q(dir / "floors.toml") + " --dry-run --json --cells 2-4"));
  EXPECT_EQ(config["regions"], all["regions"]);
  EXPECT_EQ(config["cell_ids"], (nlohmann::json{2, 3, 4}));

  const auto text = run_cellbake(bake("--floors all --dry-run"));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("floor 0: --region "), std::string::npos) << text.output;

  const auto unknown = run_cellbake(bake("--floors 0,7 --dry-run"));
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.output.find("floor 7"), std::string::npos) << unknown.output;
  EXPECT_NE(unknown.output.find(std::to_string(found) + " floors: 0 at z = "), std::string::npos) << unknown.output;
  EXPECT_NE(unknown.output.find("house.store.db"), std::string::npos) << unknown.output;
  const auto bad = run_cellbake(bake("--floors ground --dry-run"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--floors 'ground'"), std::string::npos) << bad.output;

  // submit passes --floors to every task.
  const auto submit = run_cellbake("submit " + q(dir / "floors.toml") + " --shards 2 --floors 0 --dry-run");
  ASSERT_EQ(submit.exit_code, 0) << submit.output;
  EXPECT_NE(submit.output.find("'--floors' '0'"), std::string::npos) << submit.output;
}

// A model in centimetres (the first-hour house x 100): the floors are those
// info finds in its units, eyes 1.7 m = 170 units above them unless given.
TEST(FloorsBakeUnits, AModelInCentimetresGetsItsEyes170UnitsAboveEachFloor) {
  TempDir dir;
  std::vector<test::HouseTriangle> house = test::house_triangles();
  for (auto& t : house)
    for (Vec3d& p : t) p = p * 100.0;
  std::ofstream(dir / "house_cm.obj", std::ios::binary) << test::triangles_obj(house);
  const auto ingest = run_cellbake("ingest " + q(dir / "house_cm.obj") + " --store " + q(dir / "cm.db") + " --quiet");
  ASSERT_EQ(ingest.exit_code, 0) << ingest.output;
  const auto info = json_of(run_cellbake("info --json " + q(dir / "cm.db")));
  const auto plan = json_of(run_cellbake("bake --store " + q(dir / "cm.db") +
                                         " --floors 0,1 --cell-size 200 --dry-run --json"));
  const auto& floors = plan["floors"];
  EXPECT_EQ(floors["units"], "centimetres");
  EXPECT_EQ(floors["eye_height"], 170.0);
  ASSERT_EQ(floors["found"].size(), info["floors"].size());
  ASSERT_EQ(plan["regions"].size(), 2u);
  for (int f = 0; f < 2; ++f) {
    EXPECT_DOUBLE_EQ(floors["found"][f].get<double>(), info["floors"][f]["height"].get<double>());
    EXPECT_NEAR(plan["regions"][f][2].get<double>(), floors["found"][f].get<double>() + 170, 0.006);
  }
  EXPECT_NEAR(plan["regions"][1][2].get<double>(), 470, 1);
  // Given, it wins.
  const auto given = json_of(run_cellbake("bake --store " + q(dir / "cm.db") +
                                          " --floors 0 --cell-size 200 --set cells.eye_height=150 --dry-run --json"));
  EXPECT_EQ(given["floors"]["eye_height"], 150.0);
}

// No cellbake-measure-* folder left in `tmp`.
bool measure_folder_left(const std::filesystem::path& tmp) {
  for (const auto& e : std::filesystem::directory_iterator(tmp))
    if (e.path().filename().string().rfind("cellbake-measure-", 0) == 0) return true;
  return false;
}

TEST_F(FloorsBake, DryRunMeasuresStratifiedCellsAndProjects) {
  TempDir dir;
  std::filesystem::create_directories(dir / "tmp");
  const auto r = json_of(test::run_shell("TMPDIR=" + q(dir / "tmp") + " " + CELLBAKE_BINARY + " " +
                                         bake("--floors all --dry-run --measure 2 --threads 2 --shards 1,4 --json "
                                              "--out " + q(dir / "never.db"))));
  EXPECT_FALSE(std::filesystem::exists(dir / "never.db"));
  EXPECT_FALSE(measure_folder_left(dir / "tmp"));
  const auto& measured = r["measured"];
  ASSERT_EQ(measured["cells"], 2) << r.dump();
  // Two floors or more: the two cells lie on different floors, the first on the lowest.
  const auto& selected = r["floors"]["selected"];
  ASSERT_GE(selected.size(), 2u);
  const std::int64_t id0 = measured["cell_ids"][0], id1 = measured["cell_ids"][1];
  EXPECT_LE(id0, selected[0]["last_id"].get<std::int64_t>());
  EXPECT_GE(id1, selected[1]["first_id"].get<std::int64_t>());
  const double per_cell = measured["cpu_seconds_per_cell"];
  EXPECT_GT(per_cell, 0);
  EXPECT_GT(measured["bytes_per_cell"].get<double>(), 0);
  EXPECT_GT(measured["peak_rss_bytes"].get<double>(), 1e6);
  const auto& p = r["projection"];
  const std::uint64_t cells = r["cells_selected"];
  EXPECT_EQ(p["cells"], cells);
  EXPECT_DOUBLE_EQ(p["cpu_seconds"].get<double>(), per_cell * double(cells));
  EXPECT_DOUBLE_EQ(p["wall_seconds"].get<double>(), per_cell * double((cells + 1) / 2));
  ASSERT_EQ(p["slurm"].size(), 2u);
  EXPECT_EQ(p["slurm"][1]["shards"], 4);
  EXPECT_EQ(p["slurm"][1]["cells_per_shard"], (cells + 3) / 4);

  const auto text = run_cellbake(bake("--floors 0 --dry-run --measure 1 --threads 1 --out " + q(dir / "never.db")));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("measured: 1 cell "), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("on one machine with 1 thread;"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("on Slurm, 10 shards of 1 thread each:"), std::string::npos) << text.output;

  const auto no_dry = run_cellbake(bake("--floors 0 --measure 1 --out " + q(dir / "never.db")));
  EXPECT_NE(no_dry.exit_code, 0);
  EXPECT_FALSE(std::filesystem::exists(dir / "never.db"));
}

TEST_F(FloorsBake, CtrlCDuringTheMeasurementRemovesItsFolder) {
  TempDir dir;
  std::filesystem::create_directories(dir / "tmp");
  const std::string cmd = "TMPDIR=" + q(dir / "tmp") + " exec " + CELLBAKE_BINARY + " " +
                          bake("--floors all --dry-run --measure 40 --threads 1 --out " + q(dir / "never.db")) +
                          " >/dev/null 2>" + q(dir / "err.txt");
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait for the child bake's database, then interrupt the command (it passes SIGINT on).
  bool started = false;
  for (int i = 0; i < 1200 && !started; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    for (const auto& e : std::filesystem::directory_iterator(dir / "tmp"))
      started = started || std::filesystem::exists(e.path() / "cells.db");
  }
  ASSERT_TRUE(started);
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_FALSE(measure_folder_left(dir / "tmp"));
  std::ifstream err_file(dir / "err.txt");
  const std::string err((std::istreambuf_iterator<char>(err_file)), std::istreambuf_iterator<char>());
  EXPECT_NE(err.find("temporary database was removed; nothing written"), std::string::npos) << err;
  EXPECT_EQ(err.find("rerun the same command"), std::string::npos) << err;  // the child ended quietly
  EXPECT_FALSE(std::filesystem::exists(dir / "never.db"));
}

TEST(MeasuredEstimateFailure, AFailedMeasurementBakeLeavesNoFolder) {
  // Compact clusters 10 m apart, one chunk each; one chunk corrupt: the cells that read it fail
  // (the dry run's own checks pass: row counts are intact).
  TempDir dir;
  std::ostringstream o;
  int next = 1;
  for (int k = 0; k < 6; ++k) test::obj_box(o, next, {10.0 * k - 0.4, -0.4, -0.4}, {10.0 * k + 0.4, 0.4, 0.4}, 3);
  test::write_text(dir / "clusters.obj", o.str());
  IngestParams p;
  p.max_chunk_triangles = 128;
  ingest_models({dir / "clusters.obj"}, dir / "s.db", p, tbb_parallel_for());
  const std::string sql = "UPDATE chunks SET geometry = x'0011' WHERE min_x > 25 AND max_x < 35";
  ASSERT_EQ(std::system(("sqlite3 " + q(dir / "s.db") + " \"" + sql + "\"").c_str()), 0);
  std::filesystem::create_directories(dir / "tmp");
  const auto r = test::run_shell("TMPDIR=" + q(dir / "tmp") + " " + CELLBAKE_BINARY + " bake --store " +
                                 q(dir / "s.db") + " --region -5,-5,-5,55,5,5 --cell-size 10 --near-budget 120 " +
                                 "--face-size 16 --set sample.backend=osmesa --dry-run --measure 6 --quiet --out " +
                                 q(dir / "never.db"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("measurement bake of cells 1-6 failed"), std::string::npos) << r.output;
  EXPECT_FALSE(measure_folder_left(dir / "tmp"));
  EXPECT_FALSE(std::filesystem::exists(dir / "never.db"));
}

}  // namespace
}  // namespace cellbake
