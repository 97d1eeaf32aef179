// A new user's first hour (issue #15): looking at a model before baking
// (status / render on a geometry store), the recorded up axis, useless bakes
// refused, command-line paths relative to the current directory, and the CLI's
// help, version, unknown-command and Ctrl-C behaviour. Runs the `cellbake` binary.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/bake_config.h"
#include "runner/verify/svg_plot.h"
#include "storage/cell_db.h"
#include "tests/fixture_room_obj.h"
#include "tests/fixture_textured.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::run_cellbake;
using test::TempDir;

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// Writes the pillar room as DIR/room.obj and ingests it through the CLI.
std::filesystem::path cli_room_store(const TempDir& dir, const std::string& extra = "") {
  const auto obj = dir / "room.obj", store = dir / "room.store.db";
  std::ofstream(obj, std::ios::binary) << test::room_obj();
  const auto r = run_cellbake("ingest " + q(obj) + " --store " + q(store) + " --chunk-triangles 128 " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return store;
}

// A 12 m cube room without pillars as DIR/cube.obj, ingested through the CLI:
// no file convention and no axis the geometry prefers, so no up axis is recorded.
std::filesystem::path cli_cube_room_store(const TempDir& dir) {
  const auto obj = dir / "cube.obj", store = dir / "cube.store.db";
  std::ostringstream o;
  int next = 1;
  test::obj_box(o, next, {0, 0, 0}, {12, 12, 12}, 8);
  std::ofstream(obj, std::ios::binary) << o.str();
  const auto r = run_cellbake("ingest " + q(obj) + " --store " + q(store) + " --chunk-triangles 128");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return store;
}

// The --set and --out values of a `cellbake bake ...` example line.
struct BakeCommandOptionsLite {
  std::vector<std::string> sets;
  std::string out;
};
BakeCommandOptionsLite parse_example(const std::string& line) {
  std::istringstream words(line);
  std::string w;
  BakeCommandOptionsLite o;
  while (words >> w) {
    if (w == "--set" && words >> w) o.sets.push_back(w);
    if (w == "--out" && words >> w) o.out = w;
  }
  return o;
}

// --------------------------------------------------------------- item 1

TEST(StoreStatus, SummarisesAGeometryStoreInsteadOfRefusingIt) {
  TempDir dir;
  const auto store = cli_room_store(dir);
  const auto r = run_cellbake("status " + q(store));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("not a cellbake cell database"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("geometry store"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bounds: (0, 0, 0) .. (12, 12, 4)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("size: 12 x 12 x 4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("up axis:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("room.obj"), std::string::npos) << r.output;

  const auto j = run_cellbake("status --json " + q(store));
  ASSERT_EQ(j.exit_code, 0) << j.output;
  const auto doc = nlohmann::json::parse(j.output);
  EXPECT_EQ(doc["kind"], "geometry_store");
  EXPECT_GT(doc["triangles"].get<std::uint64_t>(), 1000u);
  EXPECT_GT(doc["chunks"].get<std::uint64_t>(), 1u);
  EXPECT_EQ(doc["textures"].get<std::uint64_t>(), 0u);
  EXPECT_EQ(doc["sources"].size(), 1u);
  EXPECT_DOUBLE_EQ(doc["size"][0].get<double>(), 12.0);
}

TEST(StoreRender, DrawsTheGroundTruthOfAStoreFromADefaultEye) {
  TempDir dir;
  const auto store = cli_room_store(dir);
  const auto png = dir / "look.png";
  const auto r = run_cellbake("render " + q(store) + " --size 64x48 --json --out " + q(png));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(std::filesystem::exists(png));
  const auto doc = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_GT(doc["triangles_truth"].get<std::uint64_t>(), 0u);
  // The default eye is outside the model's bounds and looks at its centre.
  const double ex = doc["eye"][0], ey = doc["eye"][1], ez = doc["eye"][2];
  EXPECT_FALSE(ex >= 0 && ex <= 12 && ey >= 0 && ey <= 12 && ez >= 0 && ez <= 4) << doc.dump();
  EXPECT_GT(ez, 4.0) << "above the model (z up)";
  EXPECT_DOUBLE_EQ(doc["look"][0].get<double>(), 6.0);
  EXPECT_DOUBLE_EQ(doc["look"][2].get<double>(), 2.0);

  // An explicit view works too; impostor and diff modes need a bake.
  const auto explicit_view =
      run_cellbake("render " + q(store) + " --size 32x32 --eye 6,6,2 --look 12,6,2 --mode truth --out " + q(png));
  EXPECT_EQ(explicit_view.exit_code, 0) << explicit_view.output;
  const auto impostor = run_cellbake("render " + q(store) + " --mode impostor --out " + q(png));
  EXPECT_NE(impostor.exit_code, 0);
  EXPECT_NE(impostor.output.find("only --mode truth"), std::string::npos) << impostor.output;
}


// --------------------------------------------------------------- item 2

std::string up_of(const std::filesystem::path& store) {
  const auto r = run_cellbake("status --json " + q(store));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto up = nlohmann::json::parse(r.output)["up"];
  return up.is_null() ? "unknown" : up.get<std::string>();
}

TEST(UpAxis, IngestRecordsTheFormatsAxisOrTheGivenOne) {
  TempDir dir;
  const auto glb = dir / "wall.glb";
  test::write_bytes(glb, test::textured_quad_glb(test::checker_wall(),
                                                 test::png_of_bottom_up(test::checker_texels(2, 2), 4, 4)));
  const auto glb_store = dir / "wall.store.db";
  const auto r = run_cellbake("ingest " + q(glb) + " --store " + q(glb_store));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("up axis: y (wall.glb: glTF is Y-up by specification)"), std::string::npos) << r.output;
  EXPECT_EQ(up_of(glb_store), "y");
  EXPECT_NE(run_cellbake("status " + q(glb_store)).output.find("up axis: y"), std::string::npos);

  // OBJ: no convention; the room's floor and ceiling say z (stages/model_analysis/up_axis_from_geometry.h).
  const auto obj_store = cli_room_store(dir);
  EXPECT_EQ(up_of(obj_store), "z");
  EXPECT_NE(run_cellbake("status " + q(obj_store)).output.find("up axis: z (detected from the geometry: large flat "
                                                               "surfaces face z"),
            std::string::npos);
  // A cube room: the geometry cannot tell, nothing is recorded.
  const auto cube_store = cli_cube_room_store(dir);
  EXPECT_EQ(up_of(cube_store), "unknown");
  EXPECT_NE(run_cellbake("status " + q(cube_store)).output.find("up axis: not recorded"), std::string::npos);
  // --up wins; against the geometry with a warning naming both.
  cli_room_store(dir, "--up z");
  EXPECT_EQ(up_of(obj_store), "z");
  const auto against = run_cellbake("ingest " + q(dir / "room.obj") + " --store " + q(obj_store) + " --up y");
  ASSERT_EQ(against.exit_code, 0) << against.output;
  EXPECT_NE(against.output.find("warning: the up axis recorded is y (--up) but the geometry looks z-up"),
            std::string::npos)
      << against.output;
  EXPECT_EQ(up_of(obj_store), "y");
  EXPECT_NE(run_cellbake("ingest " + q(dir / "room.obj") + " --store " + q(dir / "x.db") + " --up x").exit_code, 0);
}

TEST(UpAxis, BakeUsesTheRecordedAxisUnlessGiven) {
  TempDir dir;
  const std::string quick = " --region 5,5,1.6,7,7,1.6 --cell-size 2 --face-size 16 --set encode.image_format=png "
                            "--set samples.max=1 --set samples.initial=centre --threads 1 --quiet";
  // Not recorded: z, said in one line.
  const auto cube = cli_cube_room_store(dir);
  auto r = run_cellbake("bake --store " + q(cube) + " --out " + q(dir / "z.db") + quick);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("up axis not recorded in the store; assuming z (--up y to change)"), std::string::npos)
      << r.output;
  EXPECT_EQ(CellDb(dir / "z.db", CellDb::Mode::read_only).meta("up").value_or(""), "z");
  // Recorded y: used without a note; an explicit --up z wins, with a warning.
  const auto store = cli_room_store(dir, "--up y");
  r = run_cellbake("bake --store " + q(store) + " --out " + q(dir / "y.db") + quick);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("not recorded"), std::string::npos) << r.output;
  EXPECT_EQ(CellDb(dir / "y.db", CellDb::Mode::read_only).meta("up").value_or(""), "y");
  r = run_cellbake("bake --store " + q(store) + " --up z --out " + q(dir / "z2.db") + quick);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: the bake's up axis is z but the geometry store records y"), std::string::npos)
      << r.output;
  EXPECT_EQ(CellDb(dir / "z2.db", CellDb::Mode::read_only).meta("up").value_or(""), "z");
}

TEST(UpAxis, AnExplicitAxisKeepsItsHash) {
  // A config that sets up = "z" describes (and hashes) exactly as before,
  // whatever the store records.
  BakeConfig given = parse_bake_config("[model]\nstore = \"s.db\"\nup = \"z\"\n", "c.toml");
  const std::string before = describe_bake_config(given);
  EXPECT_TRUE(given.up_given);
  EXPECT_NE(resolve_up_axis(given, "y", "glTF").find("warning"), std::string::npos);
  EXPECT_EQ(given.up, "z");
  EXPECT_EQ(describe_bake_config(given), before);
  // Not given: the store's axis, else z with a note.
  BakeConfig open = parse_bake_config("[model]\nstore = \"s.db\"\n", "c.toml");
  EXPECT_EQ(resolve_up_axis(open, "y", ""), "");
  EXPECT_EQ(open.up, "y");
  BakeConfig unknown = parse_bake_config("[model]\nstore = \"s.db\"\n", "c.toml");
  EXPECT_NE(resolve_up_axis(unknown, "", "").find("assuming z"), std::string::npos);
  EXPECT_EQ(describe_bake_config(unknown), before);
}

// --------------------------------------------------------------- item 3

TEST(UselessBake, ARegionAwayFromTheModelIsAnError) {
  TempDir dir;
  const auto store = cli_room_store(dir);
  const auto r = run_cellbake("bake --store " + q(store) + " --region 100,100,1.6,104,104,1.6 --cell-size 2 --out " +
                              q(dir / "c.db") + " --quiet");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("region 1 (100,100,1.6 .. 104,104,1.6) does not meet the model's bounds (0,0,0 .. 12,12,4)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "c.db"));
  // Within one cell of the bounds is still allowed (eyes just outside a facade).
  const auto near = run_cellbake("bake --store " + q(store) + " --region 13,5,1.6,13.5,5.5,1.6 --cell-size 2 --out " +
                                 q(dir / "n.db") + " --face-size 16 --set samples.max=1 --set samples.initial=centre "
                                 "--set encode.image_format=png --threads 1 --quiet");
  EXPECT_EQ(near.exit_code, 0) << near.output;
}

TEST(UselessBake, ChunksTooCoarseForAnyFarFieldGetANoteWithTheIngestToRerun) {
  // The room in one default-sized chunk: every cull box reaches into it, so
  // no cell has a far field although the model exceeds the near budget.
  TempDir dir;
  const auto obj = dir / "room.obj", coarse = dir / "coarse.store.db";
  std::ofstream(obj, std::ios::binary) << test::room_obj();
  ASSERT_EQ(run_cellbake("ingest " + q(obj) + " --store " + q(coarse) + " --quiet").exit_code, 0);
  const std::string bake = " --region 5,5,1.6,7,7,1.6 --cell-size 2 --near-budget 200 --face-size 16 "
                           "--set samples.max=1 --set samples.initial=centre --threads 1";
  const auto r = run_cellbake("bake --store " + q(coarse) + bake + " --out " + q(dir / "c.db"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("no baked cell has a far field"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--chunk-triangles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(obj.string()), std::string::npos) << r.output;
  // Finer chunks give a far field, and no note.
  const auto fine = cli_room_store(dir);
  const auto f = run_cellbake("bake --store " + q(fine) + bake + " --out " + q(dir / "f.db"));
  EXPECT_EQ(f.exit_code, 0) << f.output;
  EXPECT_EQ(f.output.find("no baked cell has a far field"), std::string::npos) << f.output;
}

// --------------------------------------------------------------- item 4

TEST(ConfigPaths, CommandLineValuesAreRelativeToTheCurrentDirectory) {
  BakeConfig c = parse_bake_config("[model]\nstore = \"a.db\"\n[output]\ndatabase = \"o.db\"\n", "sub/x.toml");
  EXPECT_EQ(c.store, std::filesystem::path("sub/a.db"));  // in the file: relative to the file
  EXPECT_EQ(c.database, std::filesystem::path("sub/o.db"));
  apply_override(c, "model.store=b.db");
  apply_override(c, "output.database=out/c.db");
  EXPECT_EQ(c.store, std::filesystem::path("b.db"));  // on the command line: relative to the current directory
  EXPECT_EQ(c.database, std::filesystem::path("out/c.db"));
}

TEST(ConfigPaths, HeaderExamplesOfTheConfigsWorkFromTheRepositoryRoot) {
  const std::filesystem::path root = std::filesystem::path(CELLBAKE_SOURCE_DIR);
  for (const char* name : {"configs/house.toml", "configs/openfoam-buildings.toml"}) {
    std::ifstream in(root / name);
    std::string line, bake_line;
    while (std::getline(in, line))
      if (line.find("cellbake bake " + std::string(name)) != std::string::npos) bake_line = line;
    ASSERT_FALSE(bake_line.empty()) << name << " has no `cellbake bake " << name << "` example";
    // Take the --set/--out values as written and apply them as the command would.
    BakeCommandOptionsLite opt = parse_example(bake_line);
    BakeConfig c = load_bake_config(root / name);
    for (const auto& s : opt.sets) apply_override(c, s);
    if (!opt.out.empty()) c.database = opt.out;
    EXPECT_TRUE(c.store.is_relative() && c.store.parent_path().empty()) << name << ": " << c.store;
    EXPECT_TRUE(c.database.parent_path().empty()) << name << " writes " << c.database << " outside the current directory";
  }
}

// --------------------------------------------------------------- item 5

TEST(CellMap, PerfectCellsAreLabelledPerfectOnAnAbsoluteScale) {
  CellMap map{"map", "PSNR", true, 400, {}};
  map.scale_worst = 20, map.scale_best = 40, map.scale_unit = " dB";
  const double inf = std::numeric_limits<double>::infinity();
  map.cells = {{1, 0, 0, 4, 4, 30}, {2, 4, 0, 8, 4, 30}, {3, 8, 0, 12, 4, inf}, {4, 12, 0, 16, 4, std::nan("")}};
  const std::string svg = cell_map_svg(map);
  EXPECT_NE(svg.find("cell 3: PSNR perfect"), std::string::npos) << svg;
  EXPECT_NE(svg.find("cell 4: PSNR no data"), std::string::npos);
  // Uniformly 30 dB is yellow (half way), not red as a relative scale would draw its worst.
  EXPECT_NE(svg.find("fill=\"" + ramp_color(0.5) + "\""), std::string::npos);
  EXPECT_EQ(svg.find("fill=\"" + ramp_color(1.0) + "\" stroke"), std::string::npos);
  EXPECT_NE(svg.find("\u2264 20 dB"), std::string::npos);
  EXPECT_NE(svg.find("\u2265 40 dB"), std::string::npos);
  map.cells = {{1, 0, 0, 4, 4, 10}};
  EXPECT_NE(cell_map_svg(map).find("fill=\"" + ramp_color(1.0) + "\" stroke"), std::string::npos);  // <= 20: red
}

// --------------------------------------------------------------- item 6

TEST(Cli, HelpShowsDefaults) {
  const auto render = run_cellbake("render --help");
  for (const char* d : {"512x512", "impostor", "0.05"}) EXPECT_NE(render.output.find(d), std::string::npos) << d;
  EXPECT_NE(render.output.find("60"), std::string::npos);
  const auto bake = run_cellbake("bake --help");
  EXPECT_NE(bake.output.find("else z"), std::string::npos) << bake.output;
  EXPECT_NE(bake.output.find("100000"), std::string::npos);
  EXPECT_NE(bake.output.find("512"), std::string::npos);
}

TEST(Cli, UnknownCommandAndVersion) {
  const auto bogus = run_cellbake("bogus");
  EXPECT_EQ(bogus.exit_code, 2) << bogus.output;
  EXPECT_NE(bogus.output.find("unknown command 'bogus'"), std::string::npos) << bogus.output;
  EXPECT_NE(bogus.output.find("ingest, bake, status"), std::string::npos) << bogus.output;
  for (const char* flag : {"-V", "--version"}) {
    const auto v = run_cellbake(flag);
    EXPECT_EQ(v.exit_code, 0) << v.output;
    EXPECT_EQ(v.output.rfind("cellbake ", 0), 0u) << v.output;
  }
}

TEST(Cli, QuietAndVerboseTogetherAreAUsageError) {
  TempDir dir;
  test::write_text(dir / "x.db", "");
  for (const std::string args : {"-q -v status X", "status X --quiet --verbose", "-v info X -q"}) {
    const auto r = run_cellbake(args.substr(0, args.find('X')) + q(dir / "x.db") + args.substr(args.find('X') + 1));
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;  // like an unknown command
    EXPECT_EQ(r.output, "cellbake: -q/--quiet and -v/--verbose contradict each other: give one of them\n") << args;
  }
}

TEST(Cli, CtrlCDuringBakeSaysHowToResume) {
  TempDir dir;
  const auto store = cli_room_store(dir);
  const std::string bake = std::string(CELLBAKE_BINARY) + " bake --store " + q(store) +
                           " --region 1,1,1.6,11,11,1.6 --cell-size 0.25 --face-size 64 --near-budget 300 "
                           "--set near.budget_fraction=0 --threads 1 --out " +
                           q(dir / "c.db");
  // Background jobs of a non-interactive shell start with SIGINT ignored; bake installs its handler anyway,
  // before it prints anything: the signal goes once the log has its first line (a fixed delay raced a slow start).
  // 1600 cells: a fast machine baked all 100 cells of a 1 m grid before the signal came.
  const std::string script = bake + " > " + q(dir / "log") + " 2>&1 & pid=$!; for i in $(seq 300); do [ -s " +
                             q(dir / "log") + " ] && break; sleep 0.1; done; sleep 0.5; kill -INT $pid; wait $pid; echo rc=$?";
  std::string output;
  if (FILE* pipe = popen(script.c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, pipe)) output += buf;
    pclose(pipe);
  }
  EXPECT_NE(output.find("rc=130"), std::string::npos) << output;
  std::ifstream log(dir / "log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("interrupted \u2014 rerun the same command to resume"), std::string::npos) << text;
  EXPECT_EQ(run_cellbake("status --check " + q(dir / "c.db")).exit_code, 0);
}

}  // namespace
}  // namespace cellbake
