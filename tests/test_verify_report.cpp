// The verify report: statistics on analytic inputs, the SVG writers, view
// planning, JSON round trips, and `run_verify` end to end on a tiny bake of
// the room fixture (files written, numbers parse, rerun renders nothing new).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fixture_room_obj.h"
#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "runner/verify/svg_plot.h"
#include "runner/verify/verify_report.h"
#include "runner/verify/verify_runner.h"
#include "runner/verify/verify_views.h"
#include "storage/cell_db.h"
#include "test_support.h"
#include "viewer/baked_config_text.h"

namespace cellbake {
namespace {

using test::count_of;
using test::read_text;

constexpr double kInf = std::numeric_limits<double>::infinity();

VerifyViewResult view(VerifyViewKind kind, double psnr, double holes) {
  VerifyViewResult v;
  v.kind = kind;
  v.psnr_db = psnr;
  v.hole_fraction = holes;
  v.ssim = 0.9;
  return v;
}

TEST(VerifyStats, MedianOfOddEvenInfiniteAndEmpty) {
  EXPECT_DOUBLE_EQ(median_of({3, 1, 2}), 2);
  EXPECT_DOUBLE_EQ(median_of({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(median_of({1, kInf, 2, std::nan("")}), 2);  // NaN ignored
  EXPECT_EQ(median_of({kInf, kInf}), kInf);
  EXPECT_TRUE(std::isnan(median_of({})));
}

// The headline (median, worst, worst cell) is over the random views; the
// centre, corner and sample-point views are summarised apart.
TEST(VerifyStats, HeadlineOverRandomViewsReferenceViewsApart) {
  VerifyCellResult a, b;
  a.id = 7;
  a.views = {view(VerifyViewKind::random, 30, 0.01), view(VerifyViewKind::centre, 20, 0.2)};
  b.id = 9;
  b.views = {view(VerifyViewKind::random, kInf, 0), view(VerifyViewKind::random, 25, 0.1),
             view(VerifyViewKind::corner, 40, 0.05), view(VerifyViewKind::sample, 22, 0.3)};
  const std::vector<VerifyCellResult> cells{a, b};
  const MetricStats psnr = metric_stats(cells, verify_metrics()[0]);
  EXPECT_EQ(psnr.count, 3u);
  EXPECT_DOUBLE_EQ(psnr.median, 30);  // random: 30 inf 25
  EXPECT_DOUBLE_EQ(psnr.worst, 25);   // not the centre's 20 nor the sample's 22
  EXPECT_EQ(psnr.worst_cell, 9);
  EXPECT_EQ(psnr.worst_view, 1);
  EXPECT_DOUBLE_EQ(psnr.median_centre, 20);
  EXPECT_DOUBLE_EQ(psnr.median_corner, 40);
  EXPECT_DOUBLE_EQ(psnr.median_sample, 22);
  EXPECT_DOUBLE_EQ(psnr.median_reference, 22);  // 20 22 40

  const MetricInfo* holes = nullptr;
  for (const auto& m : verify_metrics())
    if (std::string(m.name) == "hole_fraction") holes = &m;
  ASSERT_TRUE(holes);
  const MetricStats h = metric_stats(cells, *holes);
  EXPECT_DOUBLE_EQ(h.worst, 0.1);  // lower is better: the maximum of the random views
  EXPECT_DOUBLE_EQ(h.median, 0.01);
  EXPECT_EQ(worst_view_index(b.views), 1);  // the worst random view, not the sample view's 22 dB
  EXPECT_EQ(worst_view_index({}), -1);
  EXPECT_EQ(worst_view_index({view(VerifyViewKind::centre, 9, 0)}), -1);

  const nlohmann::json s = summary_json(cells);
  EXPECT_EQ(s["views"].get<int>(), 6);
  EXPECT_DOUBLE_EQ(s["psnr_db"]["median"].get<double>(), 30);
  EXPECT_DOUBLE_EQ(s["psnr_db"]["median_reference"].get<double>(), 22);
  EXPECT_DOUBLE_EQ(s["psnr_db"]["median_corner"].get<double>(), 40);
}

// A view whose truth is blank (the model out of view) says nothing: it counts
// in no statistic and is never a cell's worst while another view shows the
// model, however low its PSNR (three stray impostor pixels on black: 3 dB).
TEST(VerifyStats, BlankTruthViewsCountInNoStatisticAndAreNeverTheWorst) {
  VerifyCellResult a;
  a.id = 3;
  a.views = {view(VerifyViewKind::random, 30, 0.01), view(VerifyViewKind::random, 3.2, 0.0),
             view(VerifyViewKind::random, 24, 0.02)};
  a.views[1].truth_blank = true;
  const MetricStats psnr = metric_stats({a}, verify_metrics()[0]);
  EXPECT_EQ(psnr.count, 2u);
  EXPECT_DOUBLE_EQ(psnr.median, 27);  // 24, 30
  EXPECT_DOUBLE_EQ(psnr.worst, 24);
  EXPECT_EQ(psnr.worst_view, 2);
  EXPECT_EQ(worst_view_index(a.views), 2);
  EXPECT_TRUE(worse_view(a.views[2], a.views[1]));
  EXPECT_FALSE(worse_view(a.views[1], a.views[2]));
  // Only blank views: no statistic, and the worst is the lowest of them.
  VerifyCellResult b;
  b.views = {view(VerifyViewKind::random, 9, 0), view(VerifyViewKind::random, 5, 0)};
  for (auto& v : b.views) v.truth_blank = true;
  EXPECT_EQ(metric_stats({b}, verify_metrics()[0]).count, 0u);
  EXPECT_TRUE(std::isnan(metric_stats({b}, verify_metrics()[0]).median));
  EXPECT_EQ(worst_view_index(b.views), 1);
}

TEST(FarBudgetSweep, ParsesSortsAndRefusesBadItems) {
  EXPECT_EQ(parse_far_budget_sweep("200000,50000,50000,100"), (std::vector<std::uint64_t>{100, 50000, 200000}));
  for (const char* bad : {"", "1,,2", "0", "-5", "1e5", "12x", "+3"})
    EXPECT_THROW(parse_far_budget_sweep(bad), std::invalid_argument) << bad;
}

// Medians per budget over the views that were drawn under it; the plot has a
// point per budget and names the truth's count; the table a row per budget.
TEST(FarBudgetSweep, MediansPerBudgetPlotAndTable) {
  const std::vector<std::vector<FarBudgetPoint>> views{
      {{1000, 500, 20}, {4000, 2000, 30}},
      {{4000, 3000, 34}, {1000, 700, 22}},
      {{1000, 600, 24}, {4000, 2500, kInf}},
  };
  const auto rows = summarise_far_budget_sweep(views);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].far_budget, 1000u);
  EXPECT_EQ(rows[0].views, 3u);
  EXPECT_DOUBLE_EQ(rows[0].triangles_median, 600);
  EXPECT_DOUBLE_EQ(rows[0].psnr_median_db, 22);
  EXPECT_DOUBLE_EQ(rows[0].psnr_worst_db, 20);
  EXPECT_DOUBLE_EQ(rows[1].triangles_median, 2500);
  EXPECT_DOUBLE_EQ(rows[1].psnr_median_db, 34);  // 30 34 inf
  const ScatterPlot plot = far_budget_sweep_plot(rows, 10000);
  EXPECT_EQ(drawable_points(plot), 2u);
  EXPECT_NE(plot.x_label.find("10k"), std::string::npos) << plot.x_label;
  const std::string table = far_budget_sweep_table_html(rows, 10000);
  EXPECT_EQ(count_of(table, "<tr>"), 3u);
  EXPECT_NE(table.find("<td>0.25</td>"), std::string::npos) << table;  // 2500 of the truth's 10000
  EXPECT_TRUE(summarise_far_budget_sweep({}).empty());
}

TEST(VerifyStats, CellJsonRoundTripsIncludingInfinitePsnr) {
  VerifyCellResult c;
  c.id = 3;
  c.bounds = {{0, 0, 0}, {2, 2, 2}};
  c.key = "abc|{}";
  c.bake_seconds = {{"sample", 1.5}, {"encode", 0.5}};
  c.bytes = 1234;
  c.views = {view(VerifyViewKind::corner, kInf, 0.25)};
  c.views[0].eye = {1, 2, 3};
  c.worst_view = 0;
  c.triptych = "views/cell_3.png";
  const VerifyCellResult r = cell_from_json(nlohmann::json::parse(to_json(c).dump()));
  EXPECT_EQ(r.id, 3);
  EXPECT_EQ(r.key, c.key);
  EXPECT_DOUBLE_EQ(r.bake_seconds_total(), 2.0);
  ASSERT_EQ(r.views.size(), 1u);
  EXPECT_EQ(r.views[0].kind, VerifyViewKind::corner);
  EXPECT_EQ(r.views[0].psnr_db, kInf);
  EXPECT_DOUBLE_EQ(r.views[0].hole_fraction, 0.25);
  EXPECT_EQ(r.views[0].eye, (Vec3d{1, 2, 3}));
}

TEST(VerifyStats, AnUnmeasuredLodCutStaysUnmeasuredThroughJson) {
  VerifyCellResult c;
  c.id = 4;
  c.bounds = {{0, 0, 0}, {2, 2, 2}};
  c.views = {view(VerifyViewKind::random, 35.0, 0.0), view(VerifyViewKind::random, 36.0, 0.0)};
  c.views[1].psnr_db_cut = kInf;  // measured, and identical to the truth
  c.views[1].psnr_gain_over_cut = psnr_difference(c.views[1].psnr_db, c.views[1].psnr_db_cut);
  const VerifyCellResult r = cell_from_json(nlohmann::json::parse(to_json(c).dump()));
  ASSERT_EQ(r.views.size(), 2u);
  EXPECT_TRUE(std::isnan(r.views[0].psnr_db_cut));
  EXPECT_TRUE(std::isnan(r.views[0].psnr_gain_over_cut));
  EXPECT_EQ(r.views[1].psnr_db_cut, kInf);
}

TEST(SvgPlot, NiceTicks) {
  EXPECT_EQ(nice_ticks(0, 10, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  // (0.95 - 0.3) / 6 = 0.108: the next nice step is 0.2.
  const std::vector<double> t = nice_ticks(0.3, 0.95, 6);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_NEAR(t[0], 0.4, 1e-12);
  EXPECT_NEAR(t[1], 0.6, 1e-12);
  EXPECT_NEAR(t[2], 0.8, 1e-12);
  EXPECT_EQ(nice_ticks(5, 5), (std::vector<double>{5}));
  EXPECT_TRUE(nice_ticks(1, 0).empty());
  EXPECT_EQ(format_tick(25000), "25k");
  EXPECT_EQ(format_tick(2e6), "2M");
}

TEST(SvgPlot, ScatterHasOneCirclePerFinitePoint) {
  ScatterPlot p{"title & more", "x", "y", false, 640, 420, {}};
  PlotSeries a{"a", "#f00", {}}, b{"b", "#00f", {}};
  for (int i = 0; i < 5; ++i) a.points.push_back({double(i), double(i * i), "p" + std::to_string(i)});
  b.points = {{1, 2, ""}, {2, kInf, ""}, {std::nan(""), 1, ""}, {3, 1, ""}};
  p.series = {a, b};
  const std::string svg = scatter_plot_svg(p);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(count_of(svg, "<circle"), 7u);
  EXPECT_EQ(drawable_points(p), 7u);
  EXPECT_NE(svg.find("title &amp; more"), std::string::npos);
  EXPECT_EQ(count_of(svg, "<rect x=\"") - 1, 2u);  // background + one legend swatch per series
  p.log_x = true;                                  // x = 0 is not drawable on a log axis
  EXPECT_EQ(count_of(scatter_plot_svg(p), "<circle"), 6u);
  ScatterPlot nothing;
  nothing.title = "t";
  const std::string empty = scatter_plot_svg(nothing);
  EXPECT_EQ(count_of(empty, "<circle"), 0u);
  EXPECT_NE(empty.find("no data"), std::string::npos);
}

TEST(SvgPlot, CellMapColoursWorstRedAndNamesIt) {
  CellMap map{"map", "PSNR", true, 400, {}};
  map.cells = {{1, 0, 0, 4, 4, 30}, {2, 4, 0, 8, 4, 20}, {3, 8, 0, 12, 4, std::nan("")}};
  const std::string svg = cell_map_svg(map);
  EXPECT_EQ(count_of(svg, "class=\"cell\""), 3u);
  EXPECT_NE(svg.find("worst: cell 2"), std::string::npos);
  EXPECT_NE(svg.find(ramp_color(1.0)), std::string::npos);  // the worst is red
  EXPECT_NE(svg.find(ramp_color(0.0)), std::string::npos);  // the best is green
  EXPECT_EQ(ramp_color(1.0), "#dc2626");
}

// Random views first (inside the navigable part, on its plane when flat,
// horizontal), then the centre and the corners pulled inside; deterministic.
TEST(VerifyViews, RandomViewsInTheNavigablePartThenCentreAndCorners) {
  const Box3d cell{{0, 0, 0}, {4, 4, 4}};
  const Box3d flat{{0, 0, 1.7}, {4, 4, 1.7}};  // a walkthrough region at eye height
  const auto views = plan_verify_views(cell, flat, {0, 0, 1}, 3, true, 42);
  ASSERT_EQ(views.size(), 8u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(views[i].kind, VerifyViewKind::random);
  EXPECT_EQ(views[3].kind, VerifyViewKind::centre);
  EXPECT_EQ(views[3].eye, (Vec3d{2, 2, 1.7}));
  for (int i = 4; i < 8; ++i) {
    EXPECT_EQ(views[i].kind, VerifyViewKind::corner);
    EXPECT_NEAR(std::abs(views[i].eye.x - 2), 1.96, 1e-12);
    EXPECT_NEAR(std::abs(views[i].eye.y - 2), 1.96, 1e-12);
  }
  for (const auto& v : views) {
    EXPECT_DOUBLE_EQ(v.eye.z, 1.7);       // at eye height
    EXPECT_DOUBLE_EQ(v.look.z, v.eye.z);  // horizontal
    EXPECT_NEAR(length(v.look - v.eye), 4, 1e-12);
    EXPECT_GE(v.eye.x, 0);
    EXPECT_LE(v.eye.x, 4);
    EXPECT_GE(v.eye.y, 0);
    EXPECT_LE(v.eye.y, 4);
  }
  const auto again = plan_verify_views(cell, flat, {0, 0, 1}, 3, true, 42);
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(again[i].eye, views[i].eye);
    EXPECT_EQ(again[i].look, views[i].look);
  }
  EXPECT_NE(plan_verify_views(cell, flat, {0, 0, 1}, 3, true, 43)[2].eye, views[2].eye);
  EXPECT_EQ(plan_verify_views(cell, flat, {0, 0, 1}, 3, false, 42).size(), 3u);

  const auto cube = plan_verify_views(cell, cell, {0, 0, 1}, 1, true, 1);
  ASSERT_EQ(cube.size(), 10u);  // 1 random, centre, 8 corners
  int low = 0, high = 0;
  for (int i = 2; i < 10; ++i) {
    EXPECT_EQ(cube[i].kind, VerifyViewKind::corner);
    low += cube[i].eye.z<1, high += cube[i].eye.z> 3;
  }
  EXPECT_EQ(low, 4);
  EXPECT_EQ(high, 4);
  EXPECT_THROW(plan_verify_views(cell, flat, {0, 0, 1}, 0, true, 1), std::invalid_argument);
  EXPECT_THROW(plan_verify_views(cell, Box3d{}, {0, 0, 1}, 1, true, 1), std::invalid_argument);
}

// The headline's eyes are uniform over the navigable part and their
// directions uniform over the circle: chi-square over an 8 x 8 grid of
// positions and 16 yaw sectors, pooled over many cells' seeds (as verify
// seeds each cell), below the 0.999 quantile of the chi-square distribution.
// The generator is deterministic, so this cannot flake; a biased plan (points
// pulled to the centre, corners or a band, yaws from a few directions) fails.
TEST(VerifyViews, RandomViewsAreUniformInPositionAndDirection) {
  const Box3d cell{{10, 20, 0}, {14, 24, 4}};
  const Box3d navigable{{10, 21, 1.5}, {14, 24, 1.5}};  // cut by the region on one side
  constexpr int kGrid = 8, kSectors = 16, kCells = 500, kPerCell = 8;
  std::vector<int> cells_hit(kGrid * kGrid, 0), sectors(kSectors, 0);
  for (int c = 0; c < kCells; ++c)
    for (const auto& v : plan_verify_views(cell, navigable, {0, 0, 1}, kPerCell, false,
                                           1 * 0x9E3779B97F4A7C15ull + std::uint64_t(c))) {
      ASSERT_EQ(v.kind, VerifyViewKind::random);
      ASSERT_GE(v.eye.y, 21);  // never outside the navigable part
      ASSERT_DOUBLE_EQ(v.eye.z, 1.5);
      const int gx = std::min(kGrid - 1, int((v.eye.x - 10) / 4 * kGrid));
      const int gy = std::min(kGrid - 1, int((v.eye.y - 21) / 3 * kGrid));
      ++cells_hit[gy * kGrid + gx];
      const double yaw = std::atan2(v.look.y - v.eye.y, v.look.x - v.eye.x) + M_PI;  // [0, 2 pi]
      ++sectors[std::min(kSectors - 1, int(yaw / (2 * M_PI) * kSectors))];
    }
  const auto chi_square = [](const std::vector<int>& counts) {
    double total = 0, chi = 0;
    for (int n : counts) total += n;
    const double expected = total / double(counts.size());
    for (int n : counts) chi += (n - expected) * (n - expected) / expected;
    return chi;
  };
  EXPECT_LT(chi_square(cells_hit), 103.4);  // 63 degrees of freedom: the 0.999 quantile
  EXPECT_LT(chi_square(sectors), 37.7);     // 15 degrees of freedom: 0.999 quantile 37.7
}

TEST(VerifyViews, RegionsFromConfigText) {
  const auto regions = regions_of_config_text("up=z\ncells.size=4\nregion=4,6,1.7,40,34,1.7\n");
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_EQ(regions[0].hi, (Vec3d{40, 34, 1.7}));
  EXPECT_THROW(regions_of_config_text("region=1,2,3\n"), std::invalid_argument);
}

// A black model (every vertex "0 0 0", no materials) bakes a black far field
// and a black truth: PSNR is +infinity, and the report must say that the
// truth views are blank rather than let that pass for a perfect bake.
TEST(VerifyRun, BlackModelReportsBlankTruthViews) {
  test::TempDir dir;
  std::ostringstream box;
  int next = 1;
  test::obj_box(box, next, {0, 0, 0}, {6, 4, 3}, 2);
  std::istringstream lines(box.str());
  std::ostringstream black;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream v(line.substr(2));
      double x, y, z;
      v >> x >> y >> z;
      black << "v " << x << " " << y << " " << z << " 0 0 0\n";
    } else {
      black << line << "\n";
    }
  }
  test::write_text(dir / "black.obj", black.str());
  IngestParams ip;
  ip.max_chunk_triangles = 128;
  ingest_models({dir / "black.obj"}, dir / "black.store.db", ip, tbb_parallel_for());
  BakeConfig c;
  c.store = dir / "black.store.db";
  c.regions = {Box3d{{2, 2, 1.5}, {2, 2, 1.5}}};
  c.cell_size = 2.0;
  c.near_budget = 0;
  c.face_size = 16;
  c.samples_initial = "centre";
  c.samples_max = 1;
  c.image_format = "png";
  c.database = dir / "cells.db";
  BakeOptions bo;
  bo.threads = 1;
  bo.quiet = true;
  ASSERT_EQ(run_bake(c, bo).cells_baked, 1u);

  VerifyOptions vo;
  vo.views_per_cell = 2;
  vo.width = vo.height = 16;
  vo.threads = 1;
  vo.quiet = true;
  vo.sample_views = false;
  vo.reference_views = false;
  const VerifySummary s = run_verify(c.database, dir / "report", vo);
  EXPECT_EQ(s.views, 2u);
  EXPECT_EQ(s.truth_blank_views, 2u);
  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "report" / "report.json"));
  EXPECT_EQ(j["summary"]["truth_blank_views"].get<int>(), 2);
  EXPECT_TRUE(j["cells"][0]["views"][0]["truth_blank"].get<bool>());
  EXPECT_NE(read_text(dir / "report" / "report.html").find("truth views are blank"), std::string::npos);

  // And the command's summary line says so (one random view and the centre: the
  // region is a point, so the navigable part has no corners apart from it).
  const auto cli =
      test::run_cellbake("verify --walk-seconds 0 " + c.database.string() + " --report " + (dir / "cli").string() +
                         " --views-per-cell 1 --size 16x16 --threads 1 --quiet");
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_NE(cli.output.find("2 of 2 truth views blank"), std::string::npos) << cli.output;
  EXPECT_NE(cli.output.find("warning: 2 of 2 truth views are blank"), std::string::npos) << cli.output;
}

// The room store's cells of 2 m over `region` (near budget 600, 32² faces) into DIR/cells.db.
BakeConfig room_cells(const test::TempDir& dir, const Box3d& region) {
  BakeConfig c;
  c.store = dir / "room.store.db";
  c.regions = {region};
  c.cell_size = 2.0;
  c.near_budget = 600;
  c.face_size = 32;
  c.database = dir / "cells.db";
  return c;
}

// Two random 64x48 views per cell (no reference views), quiet.
VerifyOptions two_small_views(int threads) {
  VerifyOptions vo;
  vo.views_per_cell = 2;
  vo.width = 64;
  vo.height = 48;
  vo.threads = threads;
  vo.quiet = true;
  vo.sample_views = false;
  vo.reference_views = false;
  return vo;
}

// A far field drawn wholly as exact geometry draws the truth itself: PSNR is
// +infinity because nothing was approximated, and verify says so (counted,
// summed up, and a note) instead of letting "inf dB" read as a perfect bake.
TEST(VerifyRun, ViewsDrawnAsExactGeometryAreCountedAsIdentical) {
  test::TempDir dir;
  test::ingest_room_store(dir.path());
  BakeConfig c = room_cells(dir, Box3d{{1, 1, 1.6}, {3, 3, 1.6}});
  c.far_choice = "geometry";
  BakeOptions bo;
  bo.threads = 1;
  bo.quiet = true;
  ASSERT_EQ(run_bake(c, bo).cells_baked, 1u);
  const VerifySummary s = run_verify(c.database, dir / "report", two_small_views(1));
  EXPECT_EQ(s.views, 2u);
  EXPECT_EQ(s.truth_blank_views, 0u);
  EXPECT_EQ(s.identical_views, 2u);
  EXPECT_TRUE(std::isinf(s.psnr_median_db));
  // Supersampled (drawn at 128x96, filtered to 64x48): exact geometry still
  // draws the truth pixel for pixel.
  VerifyOptions ss = two_small_views(1);
  ss.supersample = 2;
  const VerifySummary s2 = run_verify(c.database, dir / "report-ss", ss);
  EXPECT_EQ(s2.identical_views, 2u);
  ss.supersample = 5;
  EXPECT_THROW(run_verify(c.database, dir / "report-bad", ss), std::invalid_argument);

  const auto cli = test::run_cellbake(
      "verify --walk-seconds 0 " + c.database.string() + " --report " + (dir / "cli").string() +
      " --views-per-cell 2 --no-reference-views --no-sample-views --size 64x48 --threads 1");
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_NE(cli.output.find("2 of 2 views identical to the truth"), std::string::npos) << cli.output;
  EXPECT_NE(cli.output.find("note: every view the cells drew equals the truth"), std::string::npos)
      << cli.output;
}

TEST(VerifyRun, TinyBakeReportIsCompleteAndResumable) {
  test::TempDir dir;
  test::ingest_room_store(dir.path());
  BakeConfig c = room_cells(dir, Box3d{{1, 1, 1.6}, {5, 3, 1.6}});  // 2 x 1 cells of 2 m
  c.image_format = "png";
  c.far_choice = "tdm";  // depth meshes everywhere: finite PSNR in every view, so every plot has points
  BakeOptions bo;
  bo.threads = 2;
  bo.quiet = true;
  ASSERT_EQ(run_bake(c, bo).cells_baked, 2u);

  VerifyOptions vo = two_small_views(2);  // random views only here; reference views are checked below
  const std::filesystem::path report = dir / "report";
  const VerifySummary s = run_verify(c.database, report, vo);
  EXPECT_EQ(s.cells_selected, 2u);
  EXPECT_EQ(s.cells_rendered, 2u);
  EXPECT_EQ(s.cells_failed, 0u);
  EXPECT_EQ(s.views_rendered, 4u);
  ASSERT_TRUE(std::filesystem::exists(report / "report.html"));
  const std::string html = read_text(report / "report.html");
  // Self-contained: the cell map and plots inline (tooltips work), triptychs as data: URIs.
  EXPECT_NE(html.find("<!-- cell_map.svg -->\n<svg"), std::string::npos);
  EXPECT_EQ(count_of(html, "<svg"), 6u);  // cell map + 5 plots
  EXPECT_EQ(html.find("<img src=\"plots/"), std::string::npos);
  EXPECT_NE(html.find("<img src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos);
  EXPECT_NE(html.find("views/cell_"), std::string::npos);  // named in the alt text

  const nlohmann::json j = nlohmann::json::parse(read_text(report / "report.json"));
  ASSERT_EQ(j["cells"].size(), 2u);
  for (const auto& cell : j["cells"]) {
    ASSERT_EQ(cell["views"].size(), 2u);
    EXPECT_GT(cell["bytes"].get<std::uint64_t>(), 0u);
    EXPECT_GT(cell["bake_seconds"]["sample"].get<double>(), 0.0);
    for (const auto& v : cell["views"]) {
      const double ssim = v["ssim"].get<double>();
      EXPECT_GT(ssim, 0.0);
      EXPECT_LE(ssim, 1.0 + 1e-9);
      EXPECT_GE(v["hole_fraction"].get<double>(), 0.0);
      EXPECT_LE(v["hole_fraction"].get<double>(), 1.0);
      EXPECT_GT(v["triangles_truth"].get<std::uint64_t>(), 0u);
      EXPECT_GT(v["triangles_impostor"].get<std::uint64_t>(), 0u);
      EXPECT_GE(v["ms_truth"].get<double>(), 0.0);
      EXPECT_GE(v["distance_from_sample"].get<double>(), 0.0);
      EXPECT_TRUE(v["psnr_db"].is_null() || v["psnr_db"].get<double>() > 5.0);
    }
    for (const auto& v : cell["views"]) {
      EXPECT_EQ(v["kind"], "random");
      EXPECT_DOUBLE_EQ(v["eye"][2].get<double>(), 1.6);  // in the region's plane
    }
    EXPECT_TRUE(std::filesystem::file_size(report / cell["triptych"].get<std::string>()) > 100);
  }
  EXPECT_EQ(j["summary"]["views"].get<int>(), 4);
  EXPECT_EQ(j["summary"]["truth_blank_views"].get<int>(), 0);
  EXPECT_EQ(s.truth_blank_views, 0u);
  EXPECT_EQ(j["summary"]["psnr_db"]["count"].get<int>(), 4);
  for (const char* plot : {"psnr_vs_bake_seconds", "psnr_vs_bytes", "psnr_vs_triangles", "psnr_vs_distance",
                           "holes_vs_distance"}) {
    const std::string svg = read_text(report / "plots" / (std::string(plot) + ".svg"));
    EXPECT_EQ(svg.rfind("<svg", 0), 0u) << plot;
    EXPECT_GT(count_of(svg, "<circle"), 0u) << plot;
  }
  EXPECT_EQ(count_of(read_text(report / "cell_map.svg"), "class=\"cell\""), 2u);

  const VerifySummary again = run_verify(c.database, report, vo);
  EXPECT_EQ(again.cells_rendered, 0u);
  EXPECT_EQ(again.cells_reused, 2u);
  EXPECT_EQ(again.views_rendered, 0u);
  EXPECT_EQ(nlohmann::json::parse(read_text(report / "report.json"))["cells"].size(), 2u);

  vo.views_per_cell = 3;  // other parameters: everything is rendered again
  vo.far_budget_sweep = {1, 1000000};  // the root sample alone, and every sample
  const VerifySummary changed = run_verify(c.database, report, vo);
  EXPECT_EQ(changed.cells_rendered, 2u);
  EXPECT_EQ(changed.views_rendered, 6u);
  const nlohmann::json swept = nlohmann::json::parse(read_text(report / "report.json"));
  for (const auto& cell : swept["cells"])
    for (const auto& v : cell["views"]) {
      ASSERT_EQ(v["far_budget_sweep"].size(), 2u);
      // More budget draws at least as many triangles.
      EXPECT_LE(v["far_budget_sweep"][0]["triangles"].get<std::uint64_t>(),
                v["far_budget_sweep"][1]["triangles"].get<std::uint64_t>());
      EXPECT_EQ(v["far_budget_sweep"][1]["far_budget"].get<std::uint64_t>(), 1000000u);
    }
  EXPECT_TRUE(std::filesystem::exists(report / "plots" / "psnr_vs_triangles_far_budget.svg"));
  EXPECT_NE(read_text(report / "report.html").find("far budget swept"), std::string::npos);
  vo.far_budget_sweep.clear();

  // Views at every sample point and at the centre and corners too (after the
  // random ones, summarised apart), the sample views with the root-alone
  // columns, and the void curve and seconds per sample.
  vo.sample_views = true;
  vo.reference_views = true;
  run_verify(c.database, report, vo);
  const nlohmann::json k = nlohmann::json::parse(read_text(report / "report.json"));
  CellDb db(c.database, CellDb::Mode::read_only);
  for (const auto& cell : k["cells"]) {
    const auto row = db.get_cell(cell["id"].get<std::int64_t>(), false);
    ASSERT_TRUE(row);
    const std::size_t samples = row->samples.size();
    ASSERT_GE(samples, 5u);
    ASSERT_EQ(cell["views"].size(), 3u + 5u + samples);  // random, centre and 4 corners, samples
    ASSERT_EQ(cell["void_curve"].size(), samples);
    ASSERT_EQ(cell["sample_seconds"].size(), samples);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(cell["views"][i]["kind"], "random");
    EXPECT_EQ(cell["views"][3]["kind"], "centre");
    for (std::size_t i = 4; i < 8; ++i) EXPECT_EQ(cell["views"][i]["kind"], "corner");
    EXPECT_LT(cell["worst_view"].get<int>(), 3);  // the triptych shows a random view
    for (std::size_t i = 8; i < 8 + samples; ++i) {
      const auto& v = cell["views"][i];
      EXPECT_EQ(v["kind"], "sample");
      EXPECT_NEAR(v["distance_from_sample"].get<double>(), 0.0, 1e-9);
      EXPECT_TRUE(v.contains("psnr_db_root") && v.contains("hole_fraction_root"));
      EXPECT_GE(v["samples_drawn"].get<int>(), 1);
    }
  }
  EXPECT_TRUE(k["summary"]["psnr_db_root"].contains("median_sample"));
  EXPECT_EQ(k["summary"]["psnr_db"]["count"].get<int>(), 6);  // the headline: the random views alone
  EXPECT_TRUE(k["summary"]["psnr_db"].contains("median_reference"));
}

}  // namespace
}  // namespace cellbake
