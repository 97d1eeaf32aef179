// `cellbake walk`: the automatic path (serpentine order, spline through the
// cell centres at walking speed, smooth turns), the triptych frames, the
// summary and plot on analytic inputs, and walks over a tiny bake of the room
// fixture (PNG frames, an MP4 when ffmpeg is present, the CLI). ~10 s.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fixture_room_obj.h"
#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "runner/walk/video_writer.h"
#include "runner/walk/walk_path.h"
#include "runner/walk/walk_plot.h"
#include "runner/walk/walk_runner.h"
#include "runner/walk/walk_summary.h"
#include "test_support.h"
#include "viewer/triptych.h"

namespace cellbake {
namespace {

using test::count_of;
using test::read_text;

constexpr double kPi = 3.14159265358979323846;

// A z-up grid of cols x rows cells of `size` (ids row by row from 1), navigable at z = 1.7.
std::vector<WalkCell> grid_cells(int cols, int rows, double size) {
  std::vector<WalkCell> cells;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      WalkCell c;
      c.id = 1 + y * cols + x;
      c.gx = x, c.gy = y;
      c.bounds = {{x * size, y * size, 0}, {(x + 1) * size, (y + 1) * size, size}};
      c.navigable = {{x * size, y * size, 1.7}, {(x + 1) * size, (y + 1) * size, 1.7}};
      cells.push_back(c);
    }
  return cells;
}

double heading_deg(const PathView& v) { return std::atan2(v.look.y - v.eye.y, v.look.x - v.eye.x) * 180 / kPi; }

TEST(WalkPath, SerpentineOrderReversesEveryOtherRowOfEachFloor) {
  std::vector<WalkCell> cells = grid_cells(3, 2, 4);
  WalkCell upstairs_a = cells[0], upstairs_b = cells[1];
  upstairs_a.id = 7, upstairs_a.gz = 1, upstairs_b.id = 8, upstairs_b.gz = 1;
  cells.push_back(upstairs_b);
  cells.push_back(upstairs_a);
  std::vector<std::int64_t> order;
  for (const WalkCell& c : serpentine_order(cells, {0, 0, 1})) order.push_back(c.id);
  EXPECT_EQ(order, (std::vector<std::int64_t>{1, 2, 3, 6, 5, 4, 7, 8}));
}

TEST(WalkPath, CatmullRomPassesThroughItsPointsAndKeepsLinesStraight) {
  const std::vector<Vec3d> p{{0, 0, 1}, {4, 0, 1}, {4, 4, 1}, {0, 4, 1}};
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_NEAR(length(catmull_rom_point(p, double(i)) - p[i]), 0, 1e-9);
  const std::vector<Vec3d> line{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  const Vec3d mid = catmull_rom_point(line, 1.5);
  EXPECT_NEAR(mid.x, 1.5, 1e-9);
  EXPECT_NEAR(mid.y, 0, 1e-12);
  EXPECT_THROW(catmull_rom_point({{0, 0, 0}}, 0), std::invalid_argument);
}

TEST(WalkPath, AutoWalkThroughEveryCellAtWalkingSpeedWithSmoothTurns) {
  const std::vector<WalkCell> cells = grid_cells(3, 2, 4);
  AutoWalkParams params;  // 1.4 m/s, 24 fps
  const std::vector<PathView> views = auto_walk_path(cells, {0, 0, 1}, params);
  const double step = params.speed / params.fps;
  // The spline through 6 centres 4 m apart is at least 5 * 4 m long.
  ASSERT_GE(views.size(), std::size_t(20 / step));
  for (std::size_t i = 0; i < views.size(); ++i) {
    EXPECT_NEAR(views[i].eye.z, 1.7, 1e-9);   // eye height
    EXPECT_NEAR(views[i].look.z, 1.7, 1e-9);  // looks horizontally
    if (i == 0) continue;
    EXPECT_NEAR(length(views[i].eye - views[i - 1].eye), step, 0.02 * step) << "frame " << i;
    double turn = std::abs(heading_deg(views[i]) - heading_deg(views[i - 1]));
    turn = std::min(turn, 360 - turn);
    EXPECT_LT(turn, 8.0) << "frame " << i;  // under 190 degrees per second at 24 fps: no jump
  }
  for (const WalkCell& c : cells) {  // every cell's centre is passed
    double nearest = 1e9;
    for (const PathView& v : views) nearest = std::min(nearest, length(v.eye - c.navigable.center()));
    EXPECT_LE(nearest, step) << "cell " << c.id;
  }
  // The walk turns round at the row's end: it starts heading +x and walks the second row heading -x.
  EXPECT_NEAR(heading_deg(views[1]), 0, 10);
  EXPECT_NEAR(std::abs(heading_deg(views[views.size() * 3 / 4])), 180, 10);

  params.seconds = 2;
  EXPECT_EQ(auto_walk_path(cells, {0, 0, 1}, params).size(), 49u);
}

TEST(WalkPath, OneCellIsALoopInsideIt) {
  const std::vector<WalkCell> cells = grid_cells(1, 1, 4);
  const std::vector<PathView> views = auto_walk_path(cells, {0, 0, 1}, AutoWalkParams{});
  ASSERT_GT(views.size(), 10u);
  for (const PathView& v : views) {
    EXPECT_NEAR(length(v.eye - Vec3d{2, 2, 1.7}), 1.0, 0.02);  // radius a quarter of the side
    EXPECT_NEAR(v.look.z, 1.7, 1e-9);
  }
  EXPECT_THROW(auto_walk_path({}, {0, 0, 1}, AutoWalkParams{}), std::invalid_argument);
  AutoWalkParams bad;
  bad.speed = 0;
  EXPECT_THROW(auto_walk_path(cells, {0, 0, 1}, bad), std::invalid_argument);
}

TEST(WalkSummary, MediansPercentilesSwitchesAndFallbacks) {
  std::vector<WalkFrame> frames;
  for (int i = 0; i < 100; ++i) {
    WalkFrame f;
    f.index = i;
    f.t = i / 10.0;
    f.frame_ms = i + 1;  // 1 .. 100
    f.truth_ms = 50;
    f.psnr_db = 30 + (i % 10);
    f.cell = i < 40 ? 1 : (i < 70 ? 2 : 1);
    f.cell_switch = i == 40 || i == 70;
    frames.push_back(f);
  }
  frames[5].fallback = true, frames[5].psnr_db = std::numeric_limits<double>::infinity();
  frames[12].psnr_db = 20;
  const WalkSummary s = summarise_walk(frames, 10);
  EXPECT_EQ(s.frames, 100u);
  EXPECT_DOUBLE_EQ(s.seconds, 10);
  EXPECT_DOUBLE_EQ(s.frame_ms_median, 50.5);
  EXPECT_DOUBLE_EQ(s.frame_ms_p99, 99);
  EXPECT_DOUBLE_EQ(s.frame_ms_max, 100);
  EXPECT_DOUBLE_EQ(s.psnr_worst_db, 20);
  EXPECT_EQ(s.worst_frame, 12);
  EXPECT_EQ(s.fallback_frames, 1u);
  EXPECT_EQ(s.cell_switches, 2u);
  EXPECT_EQ(s.distinct_cells, 2u);
  EXPECT_EQ(s.cells_visited, (std::vector<std::int64_t>{1, 2, 1}));
  EXPECT_DOUBLE_EQ(s.switch_frame_ms_median, 56);  // frames 40 and 70: 41 and 71 ms
  const nlohmann::json j = walk_summary_json(s);
  EXPECT_DOUBLE_EQ(j["frame_ms"]["p99"].get<double>(), 99);
  EXPECT_EQ(j["cells_visited"].size(), 3u);
  EXPECT_NE(walk_summary_text(s).find("cells visited: 1 2 1"), std::string::npos);
  EXPECT_EQ(count_of(walk_frames_csv(frames), "\n"), 101u);
  EXPECT_DOUBLE_EQ(percentile({}, 50) == percentile({}, 50) ? 0 : 1, 1);  // NaN when empty
  EXPECT_DOUBLE_EQ(percentile({3, 1, 2}, 0), 1);
}

TEST(WalkPlot, OneDashedLinePerCellSwitchAndBothCurves) {
  std::vector<WalkFrame> frames(30);
  for (int i = 0; i < 30; ++i) {
    frames[i].index = i, frames[i].t = i / 24.0, frames[i].psnr_db = 30 + i % 3, frames[i].frame_ms = 10;
    frames[i].cell = 1 + i / 10;
    frames[i].cell_switch = i == 10 || i == 20;
  }
  const std::string svg = walk_plot_svg(frames, "walk");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_EQ(count_of(svg, "class=\"switch\""), 2u);
  EXPECT_NE(svg.find("enters cell 3"), std::string::npos);
  EXPECT_EQ(count_of(svg, "class=\"psnr\""), 1u);
  EXPECT_EQ(count_of(svg, "class=\"frame-ms\""), 1u);
  EXPECT_NE(walk_plot_svg({}, "empty").find("no frames"), std::string::npos);
}

TEST(Triptych, TruthCellsAndDifferenceSideBySide) {
  ViewFrame truth, cells;
  truth.width = cells.width = 2, truth.height = cells.height = 1;
  truth.color = {{1, 1, 1, 255}, {2, 2, 2, 255}};
  cells.color = {{3, 3, 3, 255}, {4, 4, 4, 255}};
  const std::vector<Rgba8> diff{{5, 5, 5, 255}, {6, 6, 6, 255}};
  const std::vector<Rgba8> t = triptych(truth, cells, diff, 1, {9, 9, 9, 255});
  ASSERT_EQ(triptych_width(2, 1), 8);
  ASSERT_EQ(t.size(), 8u);
  const int r[8] = {1, 2, 9, 3, 4, 9, 5, 6};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(t[i].r, r[i]) << i;
  EXPECT_EQ(rgb24(t).size(), 24u);
  EXPECT_THROW(triptych(truth, cells, {{0, 0, 0, 255}}), std::invalid_argument);
}

// Three 2 m cells of the room (one sample each, depth meshes only, 16² faces) in DIR/cells.db.
std::filesystem::path bake_three_room_cells(const test::TempDir& dir) {
  test::ingest_room_store(dir.path());
  BakeConfig c;
  c.store = dir / "room.store.db";
  c.regions = {Box3d{{1, 1, 1.6}, {7, 3, 1.6}}};
  c.cell_size = 2.0;
  c.near_budget = 600;
  c.face_size = 32;
  c.samples_initial = "centre";
  c.samples_max = 1;
  c.far_choice = "tdm";  // depth meshes: finite PSNR
  c.image_format = "png";
  c.database = dir / "cells.db";
  BakeOptions bo;
  bo.threads = 2;
  bo.quiet = true;
  EXPECT_EQ(run_bake(c, bo).cells_baked, 3u);
  return c.database;
}

TEST(WalkRun, TinyBakeAsPngFramesWithPlotAndSummary) {
  test::TempDir dir;
  const auto db = bake_three_room_cells(dir);
  WalkOptions wo;
  wo.width = 48, wo.height = 32;
  wo.fps = 12;
  wo.video = false;
  wo.quiet = true;
  const WalkResult r = run_walk(db, dir / "walk", wo);
  // Through 3 centres 2 m apart: 4 m at 1.4 m/s, 12 fps.
  EXPECT_NEAR(double(r.summary.frames), 4 / 1.4 * 12, 2.0);
  EXPECT_EQ(r.frames.size(), r.summary.frames);
  EXPECT_EQ(r.summary.cells_visited, (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(r.summary.cell_switches, 2u);
  EXPECT_EQ(r.summary.fallback_frames, 0u);
  EXPECT_GT(r.summary.psnr_worst_db, 5.0);
  EXPECT_LE(r.summary.psnr_worst_db, r.summary.psnr_median_db);
  EXPECT_GE(r.summary.frame_ms_max, r.summary.frame_ms_p99);
  EXPECT_TRUE(r.video.empty());
  for (std::size_t i = 0; i < r.frames.size(); ++i)
    EXPECT_TRUE(std::filesystem::exists(numbered_path(dir / "walk" / "frames" / "frame.png", int(i)))) << i;
  EXPECT_EQ(count_of(read_text(dir / "walk" / "walk.svg"), "class=\"switch\""), 2u);
  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "walk" / "walk.json"));
  EXPECT_EQ(j["frames"].get<std::size_t>(), r.frames.size());
  EXPECT_EQ(j["encoder"], "png");
  EXPECT_EQ(count_of(read_text(dir / "walk" / "walk.csv"), "\n"), r.frames.size() + 1);
  EXPECT_NE(read_text(dir / "walk" / "walk.txt").find("cells visited: 1 2 3"), std::string::npos);
  EXPECT_GT(std::filesystem::file_size(dir / "walk" / "worst.png"), 100u);

  // The truth drawn ahead on a second thread is the same truth: the same PSNR frame by frame.
  wo.truth_ahead = false;
  const WalkResult serial = run_walk(db, dir / "serial", wo);
  ASSERT_EQ(serial.frames.size(), r.frames.size());
  for (std::size_t i = 0; i < r.frames.size(); ++i) EXPECT_EQ(serial.frames[i].psnr_db, r.frames[i].psnr_db) << i;

  // Truth chunks hidden behind nearer ones skipped (the default) or drawn:
  // the same truth (this room has no surfaces tying in depth), so the same PSNR.
  wo.truth_ahead = true;
  wo.skip_hidden_truth = false;
  const WalkResult everything = run_walk(db, dir / "everything", wo);
  ASSERT_EQ(everything.frames.size(), r.frames.size());
  for (std::size_t i = 0; i < r.frames.size(); ++i) {
    EXPECT_EQ(everything.frames[i].psnr_db, r.frames[i].psnr_db) << i;
    EXPECT_GT(everything.frames[i].truth_triangles, 0u) << i;
    EXPECT_LE(r.frames[i].truth_triangles, everything.frames[i].truth_triangles) << i;
  }
  EXPECT_TRUE(nlohmann::json::parse(read_text(dir / "walk" / "walk.json"))["skip_hidden_truth"].get<bool>());
}

TEST(WalkRun, Mp4ThroughTheFfmpegProgram) {
  if (!find_ffmpeg()) GTEST_SKIP() << "no ffmpeg program on PATH (Debian package ffmpeg)";
  test::TempDir dir;
  const auto db = bake_three_room_cells(dir);
  WalkOptions wo;
  wo.width = 47, wo.height = 31;  // odd sizes: padded for yuv420p
  wo.fps = 12;
  wo.seconds = 1;
  wo.quiet = true;
  const WalkResult r = run_walk(db, dir / "walk", wo);
  EXPECT_EQ(r.summary.frames, 13u);
  ASSERT_FALSE(r.video.empty());
  const std::string mp4 = read_text(r.video);
  ASSERT_GT(mp4.size(), 1000u);
  EXPECT_EQ(mp4.substr(4, 4), "ftyp");
  EXPECT_FALSE(std::filesystem::exists(dir / "walk" / "walk.part.mp4"));
  EXPECT_FALSE(std::filesystem::exists(dir / "walk" / "frames"));
  EXPECT_EQ(nlohmann::json::parse(read_text(dir / "walk" / "walk.json"))["video"], "walk.mp4");
  if (std::system("command -v ffprobe >/dev/null 2>&1") == 0) {
    const auto frames = test::run_shell("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                        "stream=nb_read_frames,width,height -of csv=p=0 '" + r.video.string() + "'");
    EXPECT_EQ(frames.output, std::to_string(triptych_width(47, 2) + 1) + ",32,13\n");
  }
}

TEST(WalkCli, PathFileJsonAndErrorsNamingTheLine) {
  test::TempDir dir;
  const auto db = bake_three_room_cells(dir);
  test::write_text(dir / "path.txt", "# eye, look\n2 2 1.6 6 2 1.6\n3 2 1.6 7 2 1.6\n4 2 1.6 8 2 1.6\n5 2 1.6 9 2 1.6\n");
  const std::string base = std::string("walk '") + db.string() + "' --size 32x24 --no-video -q ";
  // No ffmpeg on PATH: PNG frames, and a note saying why.
  const auto ok = test::run_shell("env PATH=/nonexistent " + std::string(CELLBAKE_BINARY) + " walk '" + db.string() +
                                  "' --size 32x24 -q --path '" + (dir / "path.txt").string() + "' --out '" +
                                  (dir / "out").string() + "' --json");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("note: no ffmpeg program on PATH"), std::string::npos) << ok.output;
  const nlohmann::json j = nlohmann::json::parse(ok.output.substr(ok.output.find('{')));
  EXPECT_EQ(j["frames"].get<int>(), 4);
  EXPECT_EQ(j["cells_visited"], (nlohmann::json{1, 2}));
  EXPECT_EQ(j["encoder"], "png");
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "frames" / "frame_0003.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "walk.mp4"));

  test::write_text(dir / "bad.txt", "2 2 1.6 6 2 1.6\n2 2 oops\n");
  const auto bad = test::run_cellbake(base + "--path '" + (dir / "bad.txt").string() + "' --out '" +
                                      (dir / "out2").string() + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("bad.txt:2: expected six numbers"), std::string::npos) << bad.output;
  const auto both = test::run_cellbake(base + "--auto --path '" + (dir / "path.txt").string() + "' --out x");
  EXPECT_NE(both.exit_code, 0);
  const auto none = test::run_cellbake(base + "--cells 40-50 --out '" + (dir / "out3").string() + "'");
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.output.find("walk: error"), std::string::npos) << none.output;
}

}  // namespace
}  // namespace cellbake
