// What the commands print (#15 item 8): the global -q/--quiet (errors,
// warnings and the final summary) and -v/--verbose (per-cell detail), before
// or after the command; --json summaries of ingest, bake, verify and merge;
// status with the bake's parameters and the failed cells' errors; ingest's
// progress lines with their final counts, all before its summary. Runs the
// `cellbake` binary on the small pillar room.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "storage/cell_db.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::run_cellbake;
using test::TempDir;

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::size_t count_matching(const std::string& text, const std::string& pattern) {
  const std::regex re(pattern);
  std::size_t n = 0;
  for (const auto& line : lines_of(text)) n += std::regex_search(line, re);
  return n;
}

// The room as DIR/room.obj, ingested quietly into DIR/room.store.db.
std::filesystem::path room_store(const TempDir& dir) {
  std::ofstream(dir / "room.obj", std::ios::binary) << test::room_obj();
  const auto r = run_cellbake("-q ingest " + q(dir / "room.obj") + " --store " + q(dir / "room.store.db") +
                              " --chunk-triangles 128 --up z");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return dir / "room.store.db";
}

// A 2 x 2-cell bake of the room, cheap: one sample per cell, 32-pixel faces.
std::string bake_args(const std::filesystem::path& store, const std::filesystem::path& db) {
  return "bake --store " + q(store) + " --region 1,1,1.6,5,5,1.6 --cell-size 2 --near-budget 300 --face-size 32 "
         "--set near.budget_fraction=0 --set samples.max=1 --set samples.initial=centre "
         "--set encode.image_format=png --threads 2 --out " + q(db);
}

TEST(Verbosity, QuietPrintsTheSummaryOnlyAndVerboseEachCell) {
  TempDir dir;
  const auto store = room_store(dir);

  // -q after the command: no progress, the summary stays.
  const auto quiet = run_cellbake(bake_args(store, dir / "c.db") + " -q");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  EXPECT_EQ(count_matching(quiet.output, "^bake: "), 0u) << quiet.output;
  EXPECT_EQ(count_matching(quiet.output, "4 cells selected, 0 up to date, 4 baked, 0 failed"), 1u) << quiet.output;
  EXPECT_EQ(lines_of(quiet.output).size(), 1u) << quiet.output;

  // Without either: the progress line too.
  const auto normal = run_cellbake(bake_args(store, dir / "c.db") + " --force");
  ASSERT_EQ(normal.exit_code, 0) << normal.output;
  EXPECT_GE(count_matching(normal.output, "^bake: 4/4 cells \\("), 1u) << normal.output;
  EXPECT_EQ(count_matching(normal.output, "^cell \\d+ done in"), 0u) << normal.output;

  // -v before the command: one line per cell with its stage timings.
  const auto verbose = run_cellbake("-v " + bake_args(store, dir / "c.db") + " --force");
  ASSERT_EQ(verbose.exit_code, 0) << verbose.output;
  EXPECT_EQ(count_matching(verbose.output,
                           "^cell \\d+ done in [0-9.]+ s \\(cull_box [0-9.]+, sample [0-9.]+, depth_mesh [0-9.]+, "
                           "simplify [0-9.]+, far_choice [0-9.]+, encode [0-9.]+ s(, of which [a-z_]+ [0-9.]+(, [a-z_]+ [0-9.]+)*)?\\): 1 samples, "
                           "\\d+ near \\+ \\d+ "
                           "far triangles, [0-9.]+ KB$"),
            4u)
      << verbose.output;

  // Both at once is a usage error.
  const auto both = run_cellbake("-q -v status " + q(dir / "c.db"));
  EXPECT_EQ(both.exit_code, 2) << both.output;  // a usage error, like an unknown command
  EXPECT_NE(both.output.find("contradict each other"), std::string::npos) << both.output;
  // The viewer keeps its own arguments: -q after `view` is not taken by cellbake.
  EXPECT_EQ(run_cellbake("view --help-viewer -q").output.find("contradict"), std::string::npos);
}

TEST(Verbosity, IngestProgressEndsWithExactCountsBeforeItsSummary) {
  TempDir dir;
  std::ofstream(dir / "room.obj", std::ios::binary) << test::room_obj();
  const auto r = run_cellbake("ingest " + q(dir / "room.obj") + " --store " + q(dir / "s.db") + " --chunk-triangles 128");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto lines = lines_of(r.output);
  std::size_t summary = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i].rfind("ingested ", 0) == 0) summary = std::min(summary, i);
  ASSERT_LT(summary, lines.size()) << r.output;
  for (std::size_t i = summary; i < lines.size(); ++i)
    EXPECT_NE(lines[i].rfind("ingest ", 0), 0u) << "progress after the summary: " << lines[i] << "\n" << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("read (\\d+) triangles"))) << r.output;
  const std::string read = m[1];
  // The file's last progress line has its real count, not the last multiple of 65536 (0 for a small file).
  EXPECT_EQ(count_matching(r.output, "^ingest read room\\.obj: " + read + " triangles \\("), 1u) << r.output;
  EXPECT_EQ(count_matching(r.output, "^ingest chunk: \\d+ triangles \\("), 1u) << r.output;
  EXPECT_EQ(count_matching(r.output, "^ingest chunk: 0 triangles"), 0u) << r.output;

  const auto quiet = run_cellbake("ingest -q " + q(dir / "room.obj") + " --store " + q(dir / "s2.db"));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  EXPECT_EQ(count_matching(quiet.output, "^ingest "), 0u) << quiet.output;
  EXPECT_EQ(count_matching(quiet.output, "^ingested \\d+ triangles"), 1u) << quiet.output;
}

TEST(JsonSummaries, IngestBakeVerifyAndMergePrintOneJsonObject) {
  TempDir dir;
  std::ofstream(dir / "room.obj", std::ios::binary) << test::room_obj();
  const auto ingest = run_cellbake("-q ingest --json " + q(dir / "room.obj") + " --store " + q(dir / "s.db") +
                                   " --chunk-triangles 128 --up z");
  ASSERT_EQ(ingest.exit_code, 0) << ingest.output;
  const auto i = nlohmann::json::parse(ingest.output);
  EXPECT_EQ(i["store"], (dir / "s.db").string());
  EXPECT_GT(i["triangles_stored"].get<std::uint64_t>(), 1000u);
  EXPECT_EQ(i["up"], "z");
  EXPECT_EQ(i["bounds"]["max"][0].get<double>(), 12.0);
  EXPECT_EQ(i["content_hash"].get<std::string>().size(), 32u);

  const auto bake = run_cellbake(bake_args(dir / "s.db", dir / "c.db") + " --json -q");
  ASSERT_EQ(bake.exit_code, 0) << bake.output;
  const auto b = nlohmann::json::parse(bake.output);
  EXPECT_EQ(b["cells_selected"], 4);
  EXPECT_EQ(b["cells_baked"], 4);
  EXPECT_EQ(b["cells_failed"], 0);
  EXPECT_EQ(b["database"], (dir / "c.db").string());

  const auto verify = run_cellbake("verify --walk-seconds 0 " + q(dir / "c.db") + " --report " + q(dir / "report") +
                                   " --views-per-cell 1 --size 64x48 --threads 2 --json -q");
  ASSERT_EQ(verify.exit_code, 0) << verify.output;
  const auto v = nlohmann::json::parse(verify.output);
  EXPECT_EQ(v["cells_selected"], 4);
  EXPECT_EQ(v["cells_failed"], 0);
  EXPECT_GE(v["views"].get<std::uint64_t>(), 4u);
  EXPECT_TRUE(v["psnr_median_db"].is_number() || v["psnr_median_infinite"].get<bool>()) << verify.output;
  EXPECT_TRUE(std::filesystem::exists(v["report_html"].get<std::string>())) << verify.output;

  const auto verbose_verify = run_cellbake("verify --walk-seconds 0 " + q(dir / "c.db") + " --report " + q(dir / "report2") +
                                           " --views-per-cell 1 --size 64x48 --threads 2 -v");
  ASSERT_EQ(verbose_verify.exit_code, 0) << verbose_verify.output;
  EXPECT_EQ(count_matching(verbose_verify.output, "^cell \\d+: \\d+ views, median PSNR"), 4u) << verbose_verify.output;

  const auto merge = run_cellbake("merge --json " + q(dir / "m.db") + " " + q(dir / "c.db") + " " + q(dir / "none.db"));
  ASSERT_EQ(merge.exit_code, 0) << merge.output;
  const auto m = nlohmann::json::parse(merge.output.substr(merge.output.find('{')));  // after the missing-shard warning
  EXPECT_EQ(m["shards_merged"], 1);
  EXPECT_EQ(m["missing_shards"].size(), 1u);
  EXPECT_EQ(m["cells_done"], 4);
}

TEST(StatusDetail, ShowsTheBakeParametersAndEachFailedCellsError) {
  TempDir dir;
  const auto store = room_store(dir);
  const auto bake = run_cellbake(bake_args(store, dir / "c.db") + " -q");
  ASSERT_EQ(bake.exit_code, 0) << bake.output;
  {
    // Cell 2 failed, as a throwing stage records it.
    CellDb db(dir / "c.db", CellDb::Mode::read_write);
    CellRow row = *db.get_cell(2, true);
    row.status = "failed";
    row.error = "cell 2 (1,0,0) failed in stage sample: out of test luck";
    db.put_cell(row);
  }
  const auto r = run_cellbake("status " + q(dir / "c.db"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cells: 4 total, 3 done, 1 failed, 0 pending"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("bake: store " + store.string() + ", up z, cells.size 2, near.budget 300, "
                          "sample.face_size 32"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("1 region: 1,1,1.6,5,5,1.6"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("failed cells (1):\n  cell 2 (1,0,0) failed in stage sample: out of test luck\n"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("samples.void_threshold"), std::string::npos) << r.output;  // -v shows every parameter

  const auto v = run_cellbake("status -v " + q(dir / "c.db"));
  ASSERT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("  samples.void_threshold = "), std::string::npos) << v.output;
  EXPECT_NE(v.output.find("  region = 1,1,1.6,5,5,1.6"), std::string::npos) << v.output;

  const auto j = run_cellbake("status --json " + q(dir / "c.db"));
  ASSERT_EQ(j.exit_code, 0) << j.output;
  const auto doc = nlohmann::json::parse(j.output);
  ASSERT_EQ(doc["failed"].size(), 1u) << j.output;
  EXPECT_EQ(doc["failed"][0]["cell"], 2);
  EXPECT_EQ(doc["failed"][0]["error"], "cell 2 (1,0,0) failed in stage sample: out of test luck");
  ASSERT_EQ(doc["bakes"].size(), 1u) << j.output;
  EXPECT_EQ(doc["bakes"][0]["store"], store.string());
  EXPECT_EQ(doc["bakes"][0]["parameters"]["sample.face_size"], "32");
  EXPECT_EQ(doc["bakes"][0]["regions"][0], "1,1,1.6,5,5,1.6");

  // A rerun bakes the failed cell again; then nothing is listed.
  ASSERT_EQ(run_cellbake(bake_args(store, dir / "c.db") + " -q").exit_code, 0);
  const auto after = run_cellbake("status " + q(dir / "c.db"));
  EXPECT_EQ(after.output.find("failed cells"), std::string::npos) << after.output;
}

}  // namespace
}  // namespace cellbake
