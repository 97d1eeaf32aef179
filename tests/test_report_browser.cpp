// The verify report as people see it: cell-map labels readable (>= 10 px at
// the report's 1:1 scale), the distance plots left out when degenerate, and
// report.html opened in headless Chromium (Debian package chromium; skipped
// when absent): every image loads, no console or resource errors, the
// labels measure >= 10 px high at 1400 px wide, the walk's video plays.
// ~15 s with Chromium (one verify with a 1 s walk, two page loads).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <sstream>

#include "fixture_room_obj.h"
#include "pipeline/bake_config.h"
#include "pipeline/ingest.h"
#include "runner/bake_runner.h"
#include "runner/parallel.h"
#include "runner/verify/svg_plot.h"
#include "runner/verify/verify_report.h"
#include "runner/verify/verify_runner.h"
#include "runner/walk/video_writer.h"
#include "test_support.h"
#include "viewer/png_file.h"

namespace cellbake {
namespace {

using test::count_of;
using test::read_text;

// The font sizes of the map's id labels.
std::vector<double> label_fonts(const std::string& svg) {
  std::vector<double> sizes;
  const std::regex label("<text class=\"cell-label\"[^>]*font-size=\"([0-9.]+)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), label); it != std::sregex_iterator(); ++it)
    sizes.push_back(std::stod((*it)[1]));
  return sizes;
}

// The demo's layout: 9 x 7 cells of 4 m over 36 x 28 m (configs/plant-demo.toml).
std::vector<VerifyCellResult> demo_sized_cells(int cols = 9, int rows = 7, double size = 4) {
  std::vector<VerifyCellResult> cells;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      VerifyCellResult c;
      c.id = 1 + y * cols + x;
      c.bounds = {{4 + x * size, 6 + y * size, 0}, {4 + (x + 1) * size, 6 + (y + 1) * size, size}};
      for (int k = 0; k < 2; ++k) {
        VerifyViewResult v;
        v.kind = VerifyViewKind::random;
        v.psnr_db = 20 + (c.id * 7 + k) % 20;
        v.ssim = 0.9;
        v.distance_from_sample = 0.1 * double(c.id + k);
        v.triangles_truth = 100, v.triangles_impostor = 50;
        c.views.push_back(v);
      }
      cells.push_back(c);
    }
  return cells;
}

TEST(ReportMap, DemoSizedMapLabelsAreReadableAndTinyCellsSaySo) {
  CellMap map;
  map.title = "map";
  map.value_label = "median PSNR (dB)";
  for (const auto& c : demo_sized_cells())
    map.cells.push_back({c.id, c.bounds.lo.x, c.bounds.lo.y, c.bounds.hi.x, c.bounds.hi.y, 30});
  const std::string svg = cell_map_svg(map);
  const std::vector<double> fonts = label_fonts(svg);
  ASSERT_EQ(fonts.size(), 63u);  // every cell labelled
  for (const double f : fonts) EXPECT_GE(f, 10.0);
  EXPECT_EQ(svg.find("too small to label"), std::string::npos);

  // 0.1 m cells over 20 m: the map grows to its widest, and cells still too small go unlabelled, said once.
  CellMap tiny = map;
  tiny.cells.clear();
  for (int i = 0; i < 200; ++i) tiny.cells.push_back({i + 1, 0.1 * i, 0, 0.1 * (i + 1), 0.1, 30});
  const std::string tiny_svg = cell_map_svg(tiny);
  EXPECT_NE(tiny_svg.find("width=\"" + std::to_string(kCellMapMaxWidth) + "\""), std::string::npos);
  EXPECT_NE(tiny_svg.find("cells too small to label: hover them for their ids"), std::string::npos);
  for (const double f : label_fonts(tiny_svg)) EXPECT_GE(f, 10.0);
}

TEST(ReportPlots, DistancePlotsLeftOutWhenEveryViewSitsAtOneDistance) {
  test::TempDir dir;
  VerifyReportInput input;
  input.database = "cells.db";
  input.params = {{"up", "z"}};
  input.cells = demo_sized_cells(3, 1);
  for (auto& c : input.cells)
    for (auto& v : c.views) v.distance_from_sample = 0;  // every view at a sample point
  const VerifyReportFiles files = write_verify_report(dir / "a", input);
  EXPECT_FALSE(std::filesystem::exists(dir / "a" / "plots" / "psnr_vs_distance.svg"));
  EXPECT_FALSE(std::filesystem::exists(dir / "a" / "plots" / "holes_vs_distance.svg"));
  const std::string html = read_text(files.html);
  EXPECT_NE(html.find("vs distance from the sample point: not plotted"), std::string::npos);
  EXPECT_EQ(html.find("<!-- plots/psnr_vs_distance.svg"), std::string::npos);

  input.cells[0].views[0].distance_from_sample = 0.5;  // two distances: still degenerate
  write_verify_report(dir / "b", input);
  EXPECT_FALSE(std::filesystem::exists(dir / "b" / "plots" / "psnr_vs_distance.svg"));

  input.cells[1].views[0].distance_from_sample = 0.7;  // three
  const VerifyReportFiles three = write_verify_report(dir / "c", input);
  EXPECT_TRUE(std::filesystem::exists(dir / "c" / "plots" / "psnr_vs_distance.svg"));
  EXPECT_EQ(read_text(three.html).find("not plotted"), std::string::npos);
}

// --- headless Chromium ---------------------------------------------------

std::optional<std::string> find_chromium() {
  if (const char* env = std::getenv("CELLBAKE_CHROMIUM")) return std::string(env);
  for (const char* name : {"chromium", "chromium-browser"})
    if (std::system((std::string("command -v ") + name + " >/dev/null 2>&1").c_str()) == 0) return std::string(name);
  return std::nullopt;
}

// Records errors (scripts, console.error, resources that fail to load) from
// the start, then on load measures the page and appends the result as JSON.
const char* kProbe = R"(<script>
window.__probe_errors = [];
window.addEventListener('error', function (e) {
  var t = e.target;
  if (t && t !== window && t.tagName) { if (t.tagName !== 'VIDEO') __probe_errors.push('cannot load ' + t.tagName + ' ' + (t.getAttribute('alt') || t.getAttribute('src') || '').slice(0, 80)); }
  else __probe_errors.push('error: ' + e.message);
}, true);
(function () { var ce = console.error; console.error = function () { __probe_errors.push('console.error: ' + Array.prototype.join.call(arguments, ' ')); ce.apply(console, arguments); }; })();
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var labels = Array.prototype.slice.call(document.querySelectorAll('text.cell-label')).map(function (t) { return t.getBoundingClientRect().height; });
  var v = document.querySelector('video');
  function finish() {
    var out = {images: imgs.length,
               broken: imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); }).map(function (i) { return i.alt; }),
               errors: __probe_errors, labels: labels.length, min_label_px: labels.length ? Math.min.apply(null, labels) : null,
               page_width: window.innerWidth,
               video: v ? {error: v.error ? v.error.code : 0, ready: v.readyState, width: v.videoWidth} : null};
    var pre = document.createElement('pre'); pre.id = 'probe-result'; pre.textContent = JSON.stringify(out); document.body.appendChild(pre);
  }
  if (v && v.readyState < 1 && !v.error) { v.addEventListener('loadedmetadata', finish); v.addEventListener('error', finish); } else finish();
});
</script>
)";

// Opens a copy of `report` with the probe in headless Chromium at 1400 px
// wide and returns the probe's result (or null with `failure` set).
nlohmann::json open_in_chromium(const std::string& chromium, const std::filesystem::path& report,
                                const test::TempDir& dir, std::string& failure) {
  std::string html = read_text(report);
  const auto head = html.find("<head>");
  if (head == std::string::npos) {
    failure = "no <head> in " + report.string();
    return nullptr;
  }
  html.insert(head + 6, kProbe);
  const std::filesystem::path probe = report.parent_path() / "probe.html";
  test::write_text(probe, html);
  const auto r = test::run_shell("timeout 120 " + chromium +
                                 " --headless --no-sandbox --disable-gpu --allow-file-access-from-files --no-first-run"
                                 " --user-data-dir='" + (dir / "chromium-profile").string() +
                                 "' --window-size=1400,1000 --virtual-time-budget=10000 --dump-dom 'file://" +
                                 probe.string() + "' 2>/dev/null");
  const std::smatch m = [&] {
    std::smatch s;
    std::regex_search(r.output, s, std::regex("<pre id=\"probe-result\">(.*?)</pre>"));
    return s;
  }();
  if (m.empty()) {
    failure = "Chromium printed no probe result (exit " + std::to_string(r.exit_code) + "): " + r.output.substr(0, 2000);
    return nullptr;
  }
  std::string json = m[1];
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"&lt;", "<"}, {"&gt;", ">"}, {"&amp;", "&"}})
    for (auto p = json.find(from); p != std::string::npos; p = json.find(from, p + 1)) json.replace(p, from.size(), to);
  return nlohmann::json::parse(json);
}

void expect_page_sound(const nlohmann::json& page, std::size_t cell_labels) {
  EXPECT_EQ(page["page_width"].get<int>(), 1400) << page.dump();
  EXPECT_GT(page["images"].get<int>(), 0) << page.dump();
  EXPECT_TRUE(page["broken"].empty()) << page.dump();
  EXPECT_TRUE(page["errors"].empty()) << page.dump();
  EXPECT_EQ(page["labels"].get<std::size_t>(), cell_labels) << page.dump();
  EXPECT_GE(page["min_label_px"].get<double>(), 10.0) << page.dump();
}

TEST(ReportBrowser, DemoSizedReportLoadsEveryImageWithReadableLabels) {
  const auto chromium = find_chromium();
  if (!chromium) GTEST_SKIP() << "no chromium on PATH (Debian package chromium; scripts/install-deps.sh test)";
  test::TempDir dir;
  VerifyReportInput input;
  input.database = "cells.db";
  input.params = {{"up", "z"}};
  input.cells = demo_sized_cells();
  std::filesystem::create_directories(dir / "report" / "views");
  for (int i = 0; i < 3; ++i) {  // three triptychs
    VerifyCellResult& c = input.cells[std::size_t(i)];
    c.worst_view = 0;
    c.triptych = "views/cell_" + std::to_string(c.id) + ".png";
    write_png(dir / "report" / c.triptych, 24, 8, std::vector<Rgba8>(24 * 8, Rgba8{10, 200, 30, 255}), {});
  }
  const VerifyReportFiles files = write_verify_report(dir / "report", input);
  std::string failure;
  const nlohmann::json page = open_in_chromium(*chromium, files.html, dir, failure);
  ASSERT_FALSE(page.is_null()) << failure;
  expect_page_sound(page, 63);
  EXPECT_EQ(page["images"].get<int>(), 3);
}

// verify with a 1 s walk (the one verify test that walks): the report links
// and embeds it, report.json holds its summary, and Chromium plays it.
TEST(ReportBrowser, VerifyReportWithItsWalkOpensInChromium) {
  test::TempDir dir;
  test::ingest_room_store(dir.path());
  BakeConfig c;
  c.store = dir / "room.store.db";
  c.regions = {Box3d{{1, 1, 1.6}, {5, 3, 1.6}}};  // 2 x 1 cells of 2 m
  c.cell_size = 2.0;
  c.near_budget = 600;
  c.face_size = 32;
  c.far_choice = "tdm";
  c.samples_initial = "centre";
  c.samples_max = 2;
  c.image_format = "png";
  c.database = dir / "cells.db";
  BakeOptions bo;
  bo.threads = 2;
  bo.quiet = true;
  ASSERT_EQ(run_bake(c, bo).cells_baked, 2u);
  VerifyOptions vo;
  vo.views_per_cell = 2;
  vo.width = 64, vo.height = 48;
  vo.threads = 2;
  vo.quiet = true;
  vo.reference_views = false;
  vo.walk_seconds = 1;
  const VerifySummary s = run_verify(c.database, dir / "report", vo);
  const std::string html = read_text(s.report_html);
  EXPECT_NE(html.find("<h2 id=\"walk\">Walk</h2>"), std::string::npos);
  EXPECT_LT(html.find("<a href=\"#walk\">"), html.find("<h2>Summary</h2>"));  // linked at the top
  EXPECT_EQ(count_of(html, "<!-- walk/walk.svg -->"), 1u);
  EXPECT_NE(html.find("alt=\"worst walk frame (walk/worst.png)\""), std::string::npos);
  const nlohmann::json report = nlohmann::json::parse(read_text(s.report_json));
  ASSERT_TRUE(report.contains("walk")) << report.dump();
  EXPECT_EQ(report["walk"]["frames"].get<int>(), 25);  // 1 s at 24 fps, both ends
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "walk" / "walk.svg"));
  const bool video = find_ffmpeg().has_value();
  if (video) {
    EXPECT_NE(html.find("<video controls muted preload=\"metadata\" style=\"max-width:100%\" src=\"walk/walk.mp4\">"),
              std::string::npos);
    EXPECT_TRUE(std::filesystem::exists(dir / "report" / "walk" / "walk.mp4"));
  } else {
    EXPECT_NE(html.find("href=\"walk/frames/\""), std::string::npos);
  }

  const auto chromium = find_chromium();
  if (!chromium) GTEST_SKIP() << "no chromium on PATH (Debian package chromium; scripts/install-deps.sh test)";
  std::string failure;
  const nlohmann::json page = open_in_chromium(*chromium, s.report_html, dir, failure);
  ASSERT_FALSE(page.is_null()) << failure;
  expect_page_sound(page, 2);
  EXPECT_EQ(page["images"].get<int>(), 3);  // two cells' worst views and the walk's worst frame
  if (video) {
    EXPECT_EQ(page["video"]["error"].get<int>(), 0) << page.dump();
    EXPECT_GE(page["video"]["ready"].get<int>(), 1) << page.dump();
    EXPECT_EQ(page["video"]["width"].get<int>(), 3 * 64 + 4) << page.dump();
  }
}

}  // namespace
}  // namespace cellbake
