// `cellbake info` (issue #15, "What to build" 1): floors found by casting rays
// down, a suggested bake at eye height over the main floor in the store's up
// axis, that suggestion baked (a non-empty far field), `--json`, what info says
// about a cell database; `bake --dry-run` writes nothing. The done-when of
// #15: info on a Y-up glTF and on a Z-up OBJ model file (its axis detected
// from the geometry), the ingest and bake lines it prints run as printed, a
// non-empty far field. Runs the `cellbake` binary; the floor finder itself on
// an in-memory source.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "pipeline/bake_estimate.h"
#include "stages/model_analysis/floor_finder.h"
#include "tests/fixture_house_model.h"
#include "tests/fixture_memory_chunk_source.h"
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
  EXPECT_NE(brace, std::string::npos) << r.output;
  return nlohmann::json::parse(r.output.substr(brace == std::string::npos ? 0 : brace));
}

// A generated Z-up house (ground floor at 0, upper floor at 3, roof) as a store.
std::filesystem::path house_store(const TempDir& dir) {
  const auto store = dir / "house.store.db";
  const auto r = run_cellbake("generate house --triangles 100000 --seed 1 --out " + q(dir / "house.ply") +
                              " --store " + q(store));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return store;
}

// "--region X0,Y0,Z0,X1,Y1,Z1 --cell-size C --near-budget N" from info's JSON suggestion.
std::string suggested_options(const nlohmann::json& s) {
  std::ostringstream o;
  o << "--region ";
  for (int i = 0; i < 6; ++i) o << (i ? "," : "") << s["region"][i].get<double>();
  o << " --cell-size " << s["cell_size"].get<double>() << " --near-budget "
    << s["near_budget"].get<std::uint64_t>();
  return o.str();
}

TEST(Info, FindsTheFloorsOfAZUpHouseAndSuggestsARegionAtEyeHeight) {
  TempDir dir;
  const auto store = house_store(dir);
  const auto text = run_cellbake("info " + q(store));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("triangles:"), std::string::npos)
      << text.output;  // the store facts, as status prints
  EXPECT_NE(text.output.find("floors"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("suggested bake"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("metres"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("cellbake bake --store"), std::string::npos) << text.output;

  const auto doc = json_of(run_cellbake("info --json " + q(store)));
  EXPECT_EQ(doc["kind"], "geometry_store");
  EXPECT_EQ(doc["up_used"], "z");
  bool ground = false, upper = false;
  for (const auto& f : doc["floors"]) {
    ground = ground || std::abs(f["height"].get<double>()) < 0.1;
    upper = upper || std::abs(f["height"].get<double>() - 3.0) < 0.1;
  }
  EXPECT_TRUE(ground && upper) << doc["floors"].dump();
  const auto& s = doc["suggested"];
  ASSERT_TRUE(s.is_object()) << doc.dump();
  EXPECT_NEAR(s["eye_height"].get<double>(), s["floor"].get<double>() + 1.7, 1e-9);
  EXPECT_NEAR(s["floor"].get<double>(), 0.0, 0.1);
  EXPECT_DOUBLE_EQ(s["region"][2].get<double>(), s["eye_height"].get<double>());
  EXPECT_DOUBLE_EQ(s["region"][5].get<double>(), s["eye_height"].get<double>());
  EXPECT_LT(s["region"][0].get<double>(), s["region"][3].get<double>());
  EXPECT_LT(s["region"][1].get<double>(), s["region"][4].get<double>());
  EXPECT_GE(s["cell_size"].get<double>(), 2.0);
  EXPECT_LE(s["cell_size"].get<double>(), 4.0);
  EXPECT_GT(s["cells"].get<std::uint64_t>(), 4u);
  EXPECT_LT(s["near_budget"].get<std::uint64_t>(),
            doc["triangles"].get<std::uint64_t>());  // leaves a far field
  EXPECT_GT(s["estimated_seconds"].get<double>(), 0.0);
  EXPECT_NE(s["command"].get<std::string>().find("--up z"), std::string::npos);
}

TEST(Info, BakingTheSuggestionGivesAFarField) {
  TempDir dir;
  const auto store = house_store(dir);
  const auto s = json_of(run_cellbake("info --json " + q(store)))["suggested"];
  ASSERT_TRUE(s.is_object());
  const auto db = dir / "house.cells.db";
  const auto bake = run_cellbake("bake --store " + q(store) + " --up z " + suggested_options(s) + " --out " +
                                 q(db) + " --set sample.face_size=64 --cells 10-11");
  ASSERT_EQ(bake.exit_code, 0) << bake.output;
  const auto status = json_of(run_cellbake("status --json " + q(db)));
  EXPECT_EQ(status["cells_done"].get<std::uint64_t>(), 2u) << status.dump();
  EXPECT_GT(
      status["far_triangles"].get<std::uint64_t>() + status["far_geometry_triangles"].get<std::uint64_t>(),
      0u)
      << status.dump();

  // On a cell database info points to status.
  const auto on_cells = run_cellbake("info " + q(db));
  EXPECT_EQ(on_cells.exit_code, 0) << on_cells.output;
  EXPECT_NE(on_cells.output.find("cellbake status"), std::string::npos) << on_cells.output;
}

// The pillar room turned Y-up: (x, y, z) -> (x, z, -y), ingested with --up y.
TEST(Info, UsesTheRecordedYUpAxis) {
  TempDir dir;
  std::istringstream in(test::room_obj());
  std::ostringstream out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream v(line.substr(2));
      double x, y, z;
      v >> x >> y >> z;
      std::string rest;
      std::getline(v, rest);
      out << "v " << x << " " << z << " " << -y << rest << "\n";
    } else {
      out << line << "\n";
    }
  }
  const auto obj = dir / "room_yup.obj", store = dir / "room_yup.store.db";
  std::ofstream(obj, std::ios::binary) << out.str();
  const auto ingest =
      run_cellbake("ingest " + q(obj) + " --store " + q(store) + " --chunk-triangles 128 --up y");
  ASSERT_EQ(ingest.exit_code, 0) << ingest.output;

  const auto doc = json_of(run_cellbake("info --json " + q(store)));
  EXPECT_EQ(doc["up"], "y");
  EXPECT_EQ(doc["up_used"], "y");
  const auto& s = doc["suggested"];
  ASSERT_TRUE(s.is_object()) << doc.dump();
  EXPECT_NEAR(s["floor"].get<double>(), 0.0, 0.1);
  EXPECT_DOUBLE_EQ(s["region"][1].get<double>(), s["eye_height"].get<double>());  // y is the height
  EXPECT_DOUBLE_EQ(s["region"][4].get<double>(), s["eye_height"].get<double>());
  EXPECT_LT(s["region"][2].get<double>(), s["region"][5].get<double>());  // z spans the floor
  EXPECT_NE(s["command"].get<std::string>().find("--up y"), std::string::npos);

  // The suggestion is a valid bake: a dry run accepts it and writes nothing.
  const auto db = dir / "room.cells.db";
  const auto dry = run_cellbake("bake --store " + q(store) + " --up y " + suggested_options(s) + " --out " +
                                q(db) + " --dry-run");
  EXPECT_EQ(dry.exit_code, 0) << dry.output;
  EXPECT_FALSE(std::filesystem::exists(db));
}

// The line info printed after "cellbake " run in `dir` (where its relative
// store and database names land) with this build's binary, plus `extra`.
test::CommandResult run_printed(const TempDir& dir, const std::string& line, const std::string& extra = "") {
  EXPECT_EQ(line.rfind("cellbake ", 0), 0u) << line;
  return test::run_shell("cd " + q(dir.path()) + " && " + CELLBAKE_BINARY + " " + line.substr(9) + extra);
}

// Files left in a directory (info's temporary store must be gone).
std::size_t entries(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

// Issue #15's done-when on one model file: `info MODEL --json` on the file
// itself (its temporary store under DIR/tmp, gone afterwards), the axis it
// found (`up`, and `up_source` containing `why`), then the printed ingest and
// bake lines run as printed (two cells, 64^2 faces, two threads to keep it
// short): both cells done, with a far field.
void bake_as_info_suggests(const TempDir& dir, const std::filesystem::path& model, const std::string& up,
                           const std::string& why) {
  const auto tmp = dir / "tmp";
  std::filesystem::create_directories(tmp);
  const auto info = test::run_shell("TMPDIR=" + q(tmp) + " " + CELLBAKE_BINARY + " info --json " + q(model));
  const auto doc = json_of(info);
  EXPECT_EQ(entries(tmp), 0u) << "info left its temporary store behind";
  EXPECT_EQ(doc["kind"], "model_file");
  EXPECT_EQ(doc["path"], model.string());
  EXPECT_EQ(doc["up"], up) << doc.dump();
  EXPECT_EQ(doc["up_used"], up);
  EXPECT_NE(doc["up_source"].get<std::string>().find(why), std::string::npos) << doc["up_source"];
  EXPECT_GT(doc["triangles"].get<std::uint64_t>(), 5000u);
  const auto& s = doc["suggested"];
  ASSERT_TRUE(s.is_object()) << doc.dump();
  const int u = up == "y" ? 1 : 2;
  EXPECT_NEAR(s["floor"].get<double>(), s["floor"].get<double>() < 1.5 ? 0.0 : 3.0, 0.05) << s.dump();
  EXPECT_DOUBLE_EQ(s["region"][u].get<double>(), s["eye_height"].get<double>());
  EXPECT_LT(s["near_budget"].get<std::uint64_t>(), doc["triangles"].get<std::uint64_t>());
  const std::string ingest = doc["ingest"], bake = s["command"];
  EXPECT_EQ(ingest.find(" --up"), std::string::npos) << ingest;  // ingest records the same axis by itself
  EXPECT_NE(bake.find(" --up " + up), std::string::npos) << bake;

  const auto ingested = run_printed(dir, ingest);
  ASSERT_EQ(ingested.exit_code, 0) << ingested.output;
  const auto store = json_of(run_cellbake("status --json " + q(dir / doc["store"].get<std::string>())));
  EXPECT_EQ(store["up"], up);
  EXPECT_EQ(store["content_hash"], doc["content_hash"]);  // the store info looked at
  const auto baked = run_printed(dir, bake, " --cells 1-2 --threads 2 --face-size 64");
  ASSERT_EQ(baked.exit_code, 0) << baked.output;
  const auto cells = json_of(run_cellbake("status --json " + q(dir / (model.stem().string() + ".cells.db"))));
  EXPECT_EQ(cells["cells_done"].get<std::uint64_t>(), 2u) << cells.dump();
  EXPECT_GT(cells["far_triangles"].get<std::uint64_t>() + cells["far_geometry_triangles"].get<std::uint64_t>(), 0u)
      << cells.dump();
}

TEST(Info, OnAYUpGltfPrintsIngestAndBakeLinesThatBakeAFarField) {
  TempDir dir;
  const auto gltf = test::write_y_up_gltf(dir.path(), "house", test::house_triangles());
  bake_as_info_suggests(dir, gltf, "y", "glTF is Y-up by specification; the geometry agrees");

  // The text report: the model's facts, then the two lines in order.
  const auto text = run_cellbake("info " + q(gltf));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("a model file, read into a temporary geometry store"), std::string::npos)
      << text.output;
  EXPECT_NE(text.output.find("up axis: y (house.gltf: glTF is Y-up"), std::string::npos) << text.output;
  // A small model: read with chunks small enough for a far field (tests/fixture_house_model.h: 5 520 triangles).
  const auto ingest =
      text.output.find("\n  cellbake ingest " + gltf.string() + " --store house.store.db --chunk-triangles 256\n");
  const auto bake = text.output.find("\n  cellbake bake --store house.store.db --up y ");
  EXPECT_NE(ingest, std::string::npos) << text.output;
  EXPECT_NE(bake, std::string::npos) << text.output;
  EXPECT_LT(ingest, bake);
}

TEST(Info, OnAZUpObjDetectsTheAxisFromTheGeometryAndBakesAFarField) {
  TempDir dir;
  const auto obj = dir / "house.obj";
  std::ofstream(obj, std::ios::binary) << test::triangles_obj(test::house_triangles());
  bake_as_info_suggests(dir, obj, "z", "detected from the geometry: large flat surfaces face z");
}

TEST(Info, OnAModelFileLeavesNoTemporaryStoreEvenOnError) {
  TempDir dir;
  const auto tmp = dir / "tmp";
  std::filesystem::create_directories(tmp);
  const auto bad = dir / "bad.obj";
  std::ofstream(bad, std::ios::binary) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 99\n";
  const auto r = test::run_shell("TMPDIR=" + q(tmp) + " " + CELLBAKE_BINARY + " info " + q(bad));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("bad.obj"), std::string::npos) << r.output;
  EXPECT_EQ(entries(tmp), 0u);
}

// A model the geometry cannot place (a cube): z is assumed and the ingest line says so.
TEST(Info, OnAModelWithoutAClearAxisAssumesZAndPutsItInTheIngestLine) {
  TempDir dir;
  const auto obj = dir / "cube.obj";
  std::vector<test::HouseTriangle> cube;
  test::add_box(cube, {0, 0, 0}, {8, 8, 8}, 4);
  std::ofstream(obj, std::ios::binary) << test::triangles_obj(cube);
  const auto doc = json_of(run_cellbake("info --json " + q(obj)));
  EXPECT_TRUE(doc["up"].is_null()) << doc.dump();
  EXPECT_EQ(doc["up_used"], "z");
  EXPECT_NE(doc["up_used_source"].get<std::string>().find("not conclusive"), std::string::npos) << doc.dump();
  EXPECT_NE(doc["ingest"].get<std::string>().find(" --up z"), std::string::npos) << doc.dump();
}

// A model lower than eye height above its floor (an object: its "floor" is
// its top): cells around it at its mid-height, over its footprint grown by one
// cell, and the printed bake line is one bake accepts (a region 1.7 above the
// top was refused: it must meet the model's bounds grown by one cell).
TEST(Info, ASmallObjectGetsCellsAroundItAtItsMidHeightAndABakeLineBakeAccepts) {
  TempDir dir;
  const auto obj = dir / "crate.obj";
  std::vector<test::HouseTriangle> crate;
  test::add_box(crate, {0, 0, 0}, {1.2, 0.8, 0.5}, 8);
  test::add_box(crate, {0.2, 0.2, 0.5}, {0.6, 0.5, 0.7}, 4);
  std::ofstream(obj, std::ios::binary) << test::triangles_obj(crate);
  const auto doc = json_of(run_cellbake("info --json " + q(obj) + " --up z"));
  const auto& s = doc["suggested"];
  ASSERT_TRUE(s.is_object()) << doc.dump();
  const double cell = s["cell_size"].get<double>();
  EXPECT_LT(cell, 1.0);
  EXPECT_DOUBLE_EQ(s["eye_height"].get<double>(), 0.35);  // mid-height of 0 .. 0.7
  EXPECT_DOUBLE_EQ(s["region"][0].get<double>(), -cell);  // around the 1.2 x 0.8 footprint
  EXPECT_DOUBLE_EQ(s["region"][4].get<double>(), 0.8 + cell);
  const auto text = run_cellbake("info " + q(obj) + " --up z");
  EXPECT_NE(text.output.find("the model's mid-height"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("cells around it"), std::string::npos) << text.output;

  const auto ingested = run_printed(dir, doc["ingest"].get<std::string>());
  ASSERT_EQ(ingested.exit_code, 0) << ingested.output;
  const auto dry = run_printed(dir, s["command"].get<std::string>(), " --dry-run");
  EXPECT_EQ(dry.exit_code, 0) << dry.output;
}

// Far from the origin the printed region keeps its hundredths: the house moved
// by 1e7 gets the same suggestion moved by 1e7, and as many cells (printed as
// "%.6g" it read 1e+07,...: a region of zero width, 5 cells instead of 42).
TEST(Info, FarFromTheOriginThePrintedRegionKeepsItsFractions) {
  TempDir dir;
  const auto near_store = house_store(dir), far_store = dir / "far.store.db";
  const auto ingest = run_cellbake("ingest " + q(dir / "house.ply") + " --store " + q(far_store) +
                                   " --up z --translate 1e7,-2e7,0");
  ASSERT_EQ(ingest.exit_code, 0) << ingest.output;
  const auto near = json_of(run_cellbake("info --json " + q(near_store)))["suggested"];
  const auto far = json_of(run_cellbake("info --json " + q(far_store)))["suggested"];
  ASSERT_TRUE(near.is_object() && far.is_object());
  EXPECT_EQ(far["cells"], near["cells"]);
  // The region in the printed command, parsed back.
  const std::string command = far["command"];
  const auto at = command.find("--region ") + 9;
  std::istringstream region(command.substr(at, command.find(' ', at) - at));
  const double shift[3] = {1e7, -2e7, 0};
  for (int i = 0; i < 6; ++i) {
    double v = 0;
    char comma = 0;
    region >> v;
    if (i < 5) region >> comma;
    EXPECT_NEAR(v, near["region"][i].get<double>() + shift[i % 3], 0.006) << command;
  }
  EXPECT_EQ(command.find("e+"), std::string::npos) << command;
  const auto dry = run_printed(dir, command, " --dry-run --json");
  ASSERT_EQ(dry.exit_code, 0) << dry.output;
  EXPECT_EQ(json_of(dry)["cells_selected"], near["cells"]) << dry.output;
  const auto status = run_cellbake("status " + q(far_store));
  const auto bounds = status.output.find("bounds: (");
  ASSERT_NE(bounds, std::string::npos) << status.output;
  const std::string line = status.output.substr(bounds, status.output.find('\n', bounds) - bounds);
  EXPECT_EQ(line.find("e+"), std::string::npos) << line;  // all digits, as the region
  EXPECT_NE(line.find(" -2000000"), std::string::npos) << line;
}

TEST(BakeDryRun, PrintsCellsBudgetAndEstimateAndCreatesNoFile) {
  TempDir dir;
  const auto store = house_store(dir);
  const auto db = dir / "dry.cells.db";
  const std::string bake = "bake --store " + q(store) + " --region 1,1,1.7,9,7,1.7 --cell-size 2 --out " +
                           q(db) + " --dry-run --cells 2-5";
  const auto text = run_cellbake(bake);
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_NE(text.output.find("dry run: nothing written"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("cells: 4 selected of 12"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("near budget: 10007"), std::string::npos) << text.output;  // 10 % of 100070
  EXPECT_NE(text.output.find("estimate:"), std::string::npos) << text.output;
  const auto doc = json_of(run_cellbake(bake + " --json"));
  EXPECT_EQ(doc["cells_selected"].get<std::uint64_t>(), 4u);
  EXPECT_EQ(doc["cell_ids"], nlohmann::json({2, 3, 4, 5}));
  EXPECT_GT(doc["estimated_seconds"].get<double>(), 0.0);
  EXPECT_GT(doc["estimated_bytes_per_cell"].get<double>(), 0.0);
  EXPECT_FALSE(std::filesystem::exists(db));
  EXPECT_FALSE(std::filesystem::exists(dir / "dry.cells.db.lock"));

  // Errors a bake would stop on stop a dry run too.
  const auto nothing = run_cellbake(bake + " --cells 99");
  EXPECT_NE(nothing.exit_code, 0) << nothing.output;
  EXPECT_FALSE(std::filesystem::exists(db));
}

// The floor finder on a hand-built scene: a 10 x 10 floor at 0, a 10 x 10
// slab at 2.9-3 (its underside the floor's ceiling, its top the upper floor),
// a 1 x 1 table top at 0.8 (too few rays to be a floor; the floor under it has
// no headroom) and nothing above the slab (a roof terrace).
TEST(FloorFinder, FindsFloorsWithHeadroomAsHistogramPeaks) {
  std::vector<std::array<Vec3d, 3>> tris;
  const auto quad = [&](double z, double x0, double y0, double x1, double y1, bool up) {
    const Vec3d a{x0, y0, z}, b{x1, y0, z}, c{x1, y1, z}, d{x0, y1, z};
    if (up)
      tris.push_back({a, b, c}), tris.push_back({a, c, d});
    else
      tris.push_back({a, c, b}), tris.push_back({a, d, c});
  };
  quad(0, 0, 0, 10, 10, true);
  quad(2.9, 0, 0, 10, 10, false);
  quad(3.0, 0, 0, 10, 10, true);
  quad(0.8, 4, 4, 5, 5, true);
  test::MemoryChunkSource source;
  source.add(test::make_memory_chunk(1, tris));
  FloorFinderParams p;
  p.grid = 40;
  const FloorFinderResult r = find_floors(source, p);
  EXPECT_EQ(r.rays, 1600u);
  EXPECT_EQ(r.rays_hit, 1600u);
  ASSERT_EQ(r.floors.size(), 2u);
  EXPECT_NEAR(r.floors[0].height, 0.0, 1e-9);
  EXPECT_NEAR(r.floors[1].height, 3.0, 1e-9);
  EXPECT_EQ(r.floors[0].covered_rays, r.floors[0].rays);  // under the slab
  EXPECT_EQ(r.floors[1].covered_rays, 0u);                // open sky
  EXPECT_EQ(r.floors[0].rays, 1600u - 16u);               // all but the 4 x 4 rays under the table
  EXPECT_NEAR(r.floors[0].covered_extent.lo.x, 0.125, 1e-9);
  EXPECT_NEAR(r.floors[0].covered_extent.hi.x, 9.875, 1e-9);

  p.up_axis = 1;  // seen as Y-up the quads are walls: no floors
  EXPECT_TRUE(find_floors(source, p).floors.empty());
}

TEST(BakeEstimate, ScalesTheDemosFiguresByFaceSizeAndModelSize) {
  // The demo itself (and an unknown size) gets the measured figures.
  for (std::uint64_t triangles : {std::uint64_t{2'000'000}, std::uint64_t{0}}) {
    const BakeEstimate demo = estimate_bake(63, 512, 2, triangles);
    EXPECT_DOUBLE_EQ(demo.core_seconds_per_cell, kMeasuredCoreSecondsPerCell);
    EXPECT_DOUBLE_EQ(demo.seconds, kMeasuredCoreSecondsPerCell * 63 / 2);
    EXPECT_DOUBLE_EQ(demo.bytes_per_cell, kMeasuredBytesPerCell);
    EXPECT_DOUBLE_EQ(demo.bytes, kMeasuredBytesPerCell * 63);
  }
  // duck.dae (4212 triangles): 0.26 of the demo's time measured, 0.21 estimated;
  // bytes at the 0.05 floor.
  const BakeEstimate duck = estimate_bake(63, 512, 2, 4212);
  EXPECT_NEAR(duck.core_seconds_per_cell / kMeasuredCoreSecondsPerCell, 0.214, 0.001);
  EXPECT_DOUBLE_EQ(duck.bytes_per_cell, 0.05 * kMeasuredBytesPerCell);
  // The 12.7 M plant: 2.6 measured, 2.52 estimated; bytes 5.3 measured, 5.3 estimated.
  const BakeEstimate big = estimate_bake(63, 512, 2, 12'700'000);
  EXPECT_NEAR(big.core_seconds_per_cell / kMeasuredCoreSecondsPerCell, 2.52, 0.01);
  EXPECT_NEAR(big.bytes_per_cell / kMeasuredBytesPerCell, 5.28, 0.01);
  // Larger models never cost less; smaller faces cost their pixel share.
  double previous = 0;
  for (std::uint64_t t = 1000; t < 1'000'000'000; t *= 3) {
    const double per_cell = estimate_bake(1, 512, 1, t).core_seconds_per_cell;
    EXPECT_GT(per_cell, previous) << t;
    previous = per_cell;
  }
  EXPECT_DOUBLE_EQ(estimate_bake(10, 256, 1, 500'000).core_seconds_per_cell,
                   estimate_bake(10, 512, 1, 500'000).core_seconds_per_cell / 4);
  EXPECT_DOUBLE_EQ(estimate_bake(10, 512, 4, 500'000).seconds,
                   estimate_bake(10, 512, 1, 500'000).seconds / 4);
}

}  // namespace
}  // namespace cellbake
