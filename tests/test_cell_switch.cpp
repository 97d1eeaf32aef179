// Hitch-free cell switches in the interactive viewer (issue #38 item 2):
// neighbours ranked by the walking direction (viewer/prefetch_order.h), the
// scripted walk's frame log and summary (viewer/frame_log.h), a cell's GPU
// uploads spread over calls within a budget while the previous cell stays
// drawn (SceneDrawer::upload_some, viewer/cell_switch.h), and a scripted walk
// of cellbake-view under Xvfb over a path `cellbake walk --write-path` wrote,
// its log and summary checked against the cells the path crosses.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "stages/render/gl_context.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "tests/fixture_box_store.h"
#include "tests/test_support.h"
#include "viewer/camera_path.h"
#include "viewer/cell_index.h"
#include "viewer/cell_switch.h"
#include "viewer/frame_log.h"
#include "viewer/prefetch_order.h"
#include "viewer/scene_drawer.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

// A 3 x 3 grid of unit cells (ids 1..9, row by row along x), all done but cell 9.
CellIndex grid_3x3() {
  std::vector<CellEntry> cells;
  for (int gy = 0; gy < 3; ++gy)
    for (int gx = 0; gx < 3; ++gx) {
      CellEntry e;
      e.id = 1 + gx + 3 * gy;
      e.gx = gx, e.gy = gy;
      e.bounds = Box3d{{double(gx), double(gy), 0}, {gx + 1.0, gy + 1.0, 1}};
      e.done = e.id != 9;
      cells.push_back(e);
    }
  return CellIndex(std::move(cells));
}

TEST(PrefetchOrder, TheCellAheadOfTheWalkComesFirst) {
  const CellIndex index = grid_3x3();
  const CellEntry& middle = *index.find(5);
  // Walking along +x from the middle cell's centre: cell 6 is entered first.
  PrefetchOrder order = prefetch_order(index, middle, {1.5, 1.5, 0.5}, {0.05, 0, 0}, 1.01);
  ASSERT_EQ(order.ids.size(), 7u);  // 8 neighbours, cell 9 not done
  EXPECT_EQ(order.ids.front(), 6);
  EXPECT_EQ(order.heading, 6);
  // Walking along -y near the cell's left edge: cell 2 first, then the rest by distance (4 is nearest).
  order = prefetch_order(index, middle, {1.1, 1.5, 0.5}, {0, -0.05, 0}, 1.01);
  EXPECT_EQ(order.heading, 2);
  EXPECT_EQ(order.ids[0], 2);
  EXPECT_EQ(order.ids[1], 4);
  // A still eye: by distance from the eye, ties by id.
  order = prefetch_order(index, middle, {1.5, 1.5, 0.5}, {0, 0, 0}, 1.01);
  EXPECT_EQ(order.heading, 0);
  EXPECT_EQ(order.ids, (std::vector<std::int64_t>{2, 4, 6, 8, 1, 3, 7}));
  // Walking out of the grid: no heading cell.
  order = prefetch_order(index, *index.find(4), {0.5, 1.5, 0.5}, {-0.05, 0, 0}, 1.01);
  EXPECT_EQ(order.heading, 0);
}

TEST(PrefetchOrder, RayEntryAndEyeVelocity) {
  const Box3d box{{1, 0, 0}, {2, 1, 1}};
  EXPECT_DOUBLE_EQ(ray_entry({0, 0.5, 0.5}, {0.5, 0, 0}, box), 2.0);
  EXPECT_LT(ray_entry({0, 0.5, 0.5}, {-0.5, 0, 0}, box), 0);
  EXPECT_LT(ray_entry({0, 2, 0.5}, {1, 0, 0}, box), 0);
  EXPECT_DOUBLE_EQ(ray_entry({1.5, 0.5, 0.5}, {1, 0, 0}, box), 0.0);
  EXPECT_LT(ray_entry({2, 0.5, 0.5}, {1, 0, 0}, box), 0);  // on its face, leaving
  EyeMotion motion(4);
  EXPECT_EQ(motion.velocity(), (Vec3d{0, 0, 0}));
  for (int k = 0; k < 10; ++k) motion.add({0.1 * k, 0, 1});
  EXPECT_NEAR(motion.velocity().x, 0.1, 1e-12);
  EXPECT_NEAR(motion.velocity().z, 0.0, 1e-12);
}

TEST(FrameLog, SummaryCountsSwitchesAndFindsTheWorstFrameNearOne) {
  std::vector<FrameRecord> frames;
  for (int k = 0; k < 100; ++k) {
    FrameRecord f;
    f.frame = k;
    f.cell_id = k < 40 ? 1 : (k < 70 ? 2 : 3);
    f.drawn_cell = (k >= 40 && k < 43) ? 1 : f.cell_id;  // cell 2 drawn from frame 43
    f.switched = k == 40 || k == 70;
    f.frame_ms = 10 + (k == 45 ? 30 : 0) + (k == 90 ? 50 : 0);
    f.upload_bytes = 100;
    f.cache_bytes = 1000 + k;
    f.triangles = 7;
    f.far_geometry_triangles = 5;
    f.chunk_budget = k == 40 ? 0 : 9;
    frames.push_back(f);
  }
  const FrameSummary s = summarize_frames(frames, 5000, 10);
  EXPECT_EQ(s.frames, 100u);
  EXPECT_EQ(s.switches, 2u);
  EXPECT_EQ(s.lagging_frames, 3u);
  EXPECT_DOUBLE_EQ(s.median_ms, 10);
  EXPECT_DOUBLE_EQ(s.p99_ms, 40);  // the 99th of 100 sorted: the 40 ms frame
  EXPECT_DOUBLE_EQ(s.max_ms, 60);
  EXPECT_EQ(s.max_frame, 90);
  EXPECT_DOUBLE_EQ(s.worst_near_switch_ms, 40);  // frame 90 is 20 frames after the last switch
  EXPECT_EQ(s.worst_near_switch_frame, 45);
  EXPECT_EQ(s.cache_peak_bytes, 1099u);
  EXPECT_EQ(s.upload_bytes, 10000u);
  const std::string csv = frame_log_csv(frames);
  EXPECT_EQ(test::count_of(csv, "\n"), 101u);
  EXPECT_NE(csv.find("\n40,2,1,1,10.000,"), std::string::npos) << csv.substr(0, 200);
  EXPECT_NE(csv.find(",1040,7,5,0\n"), std::string::npos) << csv.substr(0, 200);
  EXPECT_NE(csv.find(",1041,7,5,9\n"), std::string::npos) << csv.substr(0, 200);
  const std::string text = frame_summary_text(s);
  EXPECT_NE(text.find("switches: 2\n"), std::string::npos) << text;
  EXPECT_NE(text.find("p99 / median: 4.00"), std::string::npos) << text;
}

// A 4 x 4 x 3 m box with a pillar and a 2 x 2 grid of 1.5 m cells (ids 1..4),
// far fields as textured depth meshes.
class BakedBox : public ::testing::Test {
 protected:
  void SetUp() override {
    test::ingest_box_with_pillar(dir_.path());
    const auto r = test::run_cellbake("bake --store " + (dir_ / "s.db").string() +
                                      " --region=0.5,0.5,1,3.5,3.5,1 --cell-size 1.5 --face-size 32 --quiet "
                                      "--threads 1 --set far.choice=tdm --out " + db().string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  std::filesystem::path db() const { return dir_ / "cells.db"; }
  test::TempDir dir_;
};

TEST_F(BakedBox, UploadSomeSpreadsACellOverCallsAndLeavesTheDrawNothingToUpload) {
  GeometryStore store(dir_ / "s.db");
  CellDb cells(db(), CellDb::Mode::read_only);
  const DecodedCell cell = decode_cell(*cells.get_cell(1, true), &store);
  const std::size_t items = cell.faces.size() + cell.near_ids.size() + cell.far_pieces.size() + cell.far_whole_ids.size();
  ASSERT_GT(cell.faces.size(), 1u);
  const RenderCamera camera = look_at_camera({1.2, 1.2, 1}, {3, 3, 1}, {0, 0, 1}, 60, 64, 48, 0.05);
  ViewFrame staged_frame, direct_frame;
  {
    SceneDrawer drawer(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), store);
    std::size_t calls = 0, uploaded = 0;
    UploadProgress p;
    do {
      p = drawer.upload_some(cell, UploadBudget{1, 1e9});  // one face or chunk per call
      ++calls;
      EXPECT_LE(p.items, 1u);
      uploaded += p.bytes;
    } while (!p.complete && calls <= items);
    ASSERT_TRUE(p.complete);
    EXPECT_EQ(calls, items);  // every face and chunk of the box is uploaded once, one per call
    EXPECT_EQ(uploaded, drawer.uploaded_bytes());
    EXPECT_TRUE(drawer.is_prepared(cell.id));
    const std::uint64_t before = drawer.uploaded_bytes();
    const SceneFrameStats stats = drawer.draw_impostor(camera, 64, 48, cell, SceneDrawOptions{}, staged_frame);
    EXPECT_EQ(drawer.uploaded_bytes(), before);  // the draw found everything resident
    EXPECT_GT(stats.far_triangles + stats.chunk_triangles, 0u);
    // Again: everything is found cached, in one call, uploading nothing.
    p = drawer.upload_some(cell, UploadBudget{1, 1e9});
    EXPECT_TRUE(p.complete);
    EXPECT_EQ(p.bytes, 0u);
  }
  SceneDrawer direct(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), store);
  direct.draw_impostor(camera, 64, 48, cell, SceneDrawOptions{}, direct_frame);
  EXPECT_EQ(staged_frame.color, direct_frame.color);  // the same picture either way
}

TEST_F(BakedBox, TheSwitchKeepsThePreviousCellUntilTheNewOneIsUploaded) {
  GeometryStore store(dir_ / "s.db");
  CellDb cells(db(), CellDb::Mode::read_only);
  const auto one = std::make_shared<const DecodedCell>(decode_cell(*cells.get_cell(1, true), &store));
  const auto two = std::make_shared<const DecodedCell>(decode_cell(*cells.get_cell(2, true), &store));
  SceneDrawer drawer(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), store);
  CellSwitch cell_switch;
  const UploadBudget one_item{1, 1e9};
  UploadProgress spent;
  EXPECT_EQ(cell_switch.choose(one, nullptr, drawer, one_item, spent), one);  // the first cell at once
  EXPECT_EQ(spent.bytes, 0u);
  int frames_on_one = 0;
  for (int frame = 0; frame < 1000; ++frame) {
    spent = {};
    const auto drawn = cell_switch.choose(two, nullptr, drawer, one_item, spent);
    EXPECT_LE(spent.items, 1u);
    if (drawn == two) break;
    EXPECT_EQ(drawn, one);
    ++frames_on_one;
  }
  EXPECT_GT(frames_on_one, 1);
  EXPECT_EQ(cell_switch.shown(), two);
  // The eye's cell not decoded yet: the cell drawn stays.
  spent = {};
  EXPECT_EQ(cell_switch.choose(nullptr, nullptr, drawer, one_item, spent), two);
  // A heading cell is uploaded ahead with the budget the target leaves.
  spent = {};
  EXPECT_EQ(cell_switch.choose(two, one, drawer, UploadBudget{std::size_t{1} << 30, 1e9}, spent), two);
  spent = {};
  EXPECT_EQ(cell_switch.choose(one, nullptr, drawer, one_item, spent), one);  // resident: switched at once
  EXPECT_EQ(spent.bytes, 0u);
}

// The frame log's lines (header first) and the summary's "key: value" text.
std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::istringstream s(line);
    std::string field;
    while (std::getline(s, field, ',')) fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

TEST_F(BakedBox, AScriptedWalkUnderXvfbLogsEveryFrameAndCountsTheSwitches) {
  if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed";
  const auto path = dir_ / "walk.path";
  const auto written = test::run_cellbake("walk " + db().string() + " --write-path " + path.string());
  ASSERT_EQ(written.exit_code, 0) << written.output;
  const std::size_t walked = read_camera_path(path).size();
  EXPECT_NE(written.output.find(std::to_string(walked) + " views written"), std::string::npos) << written.output;
  {  // The walk ends standing still for 4 frames: from the 3rd still frame on, drawn as baked.
    std::string text = test::read_text(path), last = text.substr(0, text.size() - 1);
    last = last.substr(last.rfind('\n') + 1) + "\n";
    for (int k = 0; k < 4; ++k) text += last;
    test::write_text(path, text);
  }
  const std::vector<PathView> views = read_camera_path(path);
  ASSERT_EQ(views.size(), walked + 4);
  // The cells the path crosses, from the database's index.
  CellDb cells(db(), CellDb::Mode::read_only);
  const CellIndex index(cells);
  std::size_t crossings = 0;
  std::set<std::int64_t> visited;
  for (std::size_t k = 0; k < views.size(); ++k) {
    const CellEntry* here = index.containing(views[k].eye);
    ASSERT_NE(here, nullptr) << k;
    visited.insert(here->id);
    if (k > 0 && here != index.containing(views[k - 1].eye)) ++crossings;
  }
  ASSERT_EQ(visited.size(), 4u);  // the automatic walk goes through every cell
  for (const std::string mode : {"staged", "immediate"}) {
    SCOPED_TRACE(mode);
    const auto log = dir_ / ("frames-" + mode + ".csv");
    const auto run = test::run_shell("xvfb-run -a -s '-screen 0 640x480x24' " + std::string(CELLBAKE_BINARY) + " view " +
                                     db().string() + " --size 160x120 --cache-mb 16 --switch " + mode + " --path " +
                                     path.string() + " --frame-log " + log.string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const auto rows = read_csv(log);
    ASSERT_EQ(rows.size(), views.size() + 1) << run.output;
    EXPECT_EQ(rows[0].front(), "frame");
    std::size_t switches = 0;
    for (std::size_t k = 1; k < rows.size(); ++k) {
      ASSERT_EQ(rows[k].size(), 12u);
      EXPECT_EQ(std::stoul(rows[k][0]), k - 1);  // every frame, in order
      EXPECT_EQ(std::stoll(rows[k][1]), index.containing(views[k - 1].eye)->id);
      switches += rows[k][3] == "1";
      EXPECT_GT(std::stod(rows[k][4]), 0.0);
      EXPECT_LE(std::stoull(rows[k][8]), 16u << 20);  // cache bytes within --cache-mb
      EXPECT_GT(std::stoull(rows[k][9]), 0u);         // triangles drawn
      EXPECT_LE(std::stoull(rows[k][10]), std::stoull(rows[k][9]));  // of them exact far geometry
      // The frame-time budget (default 66 ms) from the first frame on, while the view moves.
      const bool still = k > views.size() - 2;  // the last two frames: their view held for 3 and 4 frames
      EXPECT_EQ(std::stoull(rows[k][11]) == 0, still) << k;
    }
    EXPECT_EQ(switches, crossings);
    unsigned long frames = 0, summary_switches = 0;
    double peak = -1, cap = -1;
    const auto at = [&](const char* key) {
      const auto p = run.output.find(key);
      return p == std::string::npos ? std::string() : run.output.substr(p + std::strlen(key));
    };
    EXPECT_EQ(std::sscanf(at("  frames: ").c_str(), "%lu", &frames), 1) << run.output;
    EXPECT_EQ(std::sscanf(at("  switches: ").c_str(), "%lu", &summary_switches), 1) << run.output;
    EXPECT_EQ(std::sscanf(at("  cache MB: ").c_str(), "peak %lf, cap %lf", &peak, &cap), 2) << run.output;
    EXPECT_EQ(frames, views.size());
    EXPECT_EQ(summary_switches, crossings);
    EXPECT_GT(peak, 0);
    EXPECT_LE(peak, cap);
    EXPECT_DOUBLE_EQ(cap, 16.0);
  }
}

}  // namespace
}  // namespace cellbake
