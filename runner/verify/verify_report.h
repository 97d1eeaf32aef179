// The `cellbake verify` report: per-view and per-cell results of rendering a
// view cell's impostor against the ground truth, their statistics (medians and
// worst values), their JSON form (report.json and the resume file), and the
// report folder (report.html with inline CSS, SVG plots, the cell map).
// Everything but write_verify_report is pure; none of it needs GL.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "runner/verify/far_budget_sweep.h"
#include "runner/verify/verify_views.h"
#include "runner/verify/verify_walk_section.h"
#include "stages/geometry.h"
#include "storage/output_file.h"

namespace cellbake {

struct VerifyViewResult {
  VerifyViewKind kind = VerifyViewKind::centre;
  Vec3d eye, look;
  double distance_from_sample = 0;  // eye to the nearest panoramic sample point of the cell, model units
  double psnr_db = 0;               // +infinity when the images are identical
  double ssim = 0, hole_fraction = 0, skin_fraction = 0, extra_fraction = 0, depth_error_median = 0;
  // The same view drawn with the root sample alone (the single-sample far
  // field, `render --max-samples 1`), for the 1-sample vs all-samples columns.
  double psnr_db_root = std::numeric_limits<double>::quiet_NaN();
  double hole_fraction_root = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t samples_drawn = 0;  // samples whose far field the impostor drew
  // The truth showed one colour over every covered pixel, or covered nothing
  // (is_blank, viewer/image_metrics.h): its PSNR says nothing.
  bool truth_blank = false;
  std::uint64_t triangles_impostor = 0, triangles_truth = 0;
  // triangles_impostor / triangles_truth: what the cell draws (near field,
  // far geometry, depth meshes) against the frustum-culled model (issue #13:
  // at most 1). NaN when the truth draws nothing.
  double triangle_ratio = std::numeric_limits<double>::quiet_NaN();
  double ms_impostor = 0, ms_truth = 0;  // warm frame, wall clock
  // `verify --lod-cut` (NaN otherwise): the model drawn as a view-dependent
  // cut through the store's chunk levels (stages/far/lod_cut.h), the yardstick
  // of issue #35: with the impostor's triangles (at the threshold that fits
  // them), and at 1 pixel of error.
  double psnr_db_cut = std::numeric_limits<double>::quiet_NaN();
  double cut_error_px = std::numeric_limits<double>::quiet_NaN();
  double psnr_gain_over_cut = std::numeric_limits<double>::quiet_NaN();  // psnr_db - psnr_db_cut
  double psnr_db_cut_1px = std::numeric_limits<double>::quiet_NaN();
  double triangles_cut_1px = std::numeric_limits<double>::quiet_NaN();
  // The view drawn once more per budget of `verify --far-budget-sweep` (random views only).
  std::vector<FarBudgetPoint> far_budget_sweep;
};

struct VerifyCellResult {
  std::int64_t id = 0;
  Box3d bounds;
  std::string key;  // content hash + verify parameters: equal keys need no re-render
  std::map<std::string, double> bake_seconds;  // per stage, from the cell database
  std::uint64_t bytes = 0, near_triangles = 0, far_triangles = 0;
  std::uint64_t far_geometry_triangles = 0;  // exact far geometry stored (issue #13)
  std::uint64_t colour_bytes = 0, mesh_bytes = 0, near_list_bytes = 0;  // stored bytes by kind (issue #16)
  std::vector<double> void_curve;  // per sample in the order taken: worst candidate's void fraction after it
                                   // (-1: not measured)
  std::vector<double> sample_seconds;  // bake seconds per sample, same order
  std::string error;                   // non-empty when the cell could not be verified (views then empty)
  std::string
      triptych;  // its worst view as truth | impostor | error image, path relative to the report folder
  int worst_view = -1;  // index into views of that view
  std::vector<VerifyViewResult> views;
  double bake_seconds_total() const;
};

// Median of the finite-or-infinite (not NaN) values: for an even count the mean
// of the two middle ones; NaN when there are none. Does not modify `values`.
double median_of(const std::vector<double>& values);

// a - b for PSNRs that may be +infinity (identical images): 0 when both are,
// +/-infinity when one is; NaN when either is NaN.
double psnr_difference(double a, double b);

// One metric's statistics. The headline — count, median, worst — is over the
// random views (runner/verify/verify_views.h: uniform over each cell's
// navigable part, what a person walking there sees); the reference views
// (centre, corners, sample points) are summarised apart.
struct MetricStats {
  std::size_t count = 0;  // non-NaN values of random views
  double median = std::numeric_limits<double>::quiet_NaN();
  double worst = std::numeric_limits<double>::quiet_NaN();  // minimum when higher is better, else maximum
  std::int64_t worst_cell = 0;  // the cell of the (first) worst value; 0 when count == 0
  int worst_view = -1;          // its index in that cell's views
  double median_centre = std::numeric_limits<double>::quiet_NaN();     // over centre views only
  double median_corner = std::numeric_limits<double>::quiet_NaN();     // over corner views only
  double median_sample = std::numeric_limits<double>::quiet_NaN();     // over views at sample points only
  double median_reference = std::numeric_limits<double>::quiet_NaN();  // over all three kinds above
};

// The metrics summarised, each with whether higher is better.
struct MetricInfo {
  const char* name;  // report.json key, e.g. "psnr_db"
  bool higher_is_better;
  double VerifyViewResult::*field;
};
const std::vector<MetricInfo>& verify_metrics();

// Statistics of one metric (MetricStats) over the views of every cell whose truth is not
// blank (a blank truth, the model out of view or one colour, says nothing;
// VerifySummary counts those views), cells in the given order, views in
// order: ties for the worst go to the first. Deterministic.
MetricStats metric_stats(const std::vector<VerifyCellResult>& cells, const MetricInfo& metric);

// Whether view `a` counts as worse than `b`: a view whose truth is not blank
// before one whose truth is, then the lower PSNR, then the larger hole fraction.
bool worse_view(const VerifyViewResult& a, const VerifyViewResult& b);

// The view of a cell that counts as its worst, shown as its triptych: the
// worst of its random (headline) views by worse_view, ties to the lower
// index; -1 when the cell has no random views.
int worst_view_index(const std::vector<VerifyViewResult>& views);

// JSON forms (non-finite numbers as null, read back as +infinity for the
// PSNRs and NaN otherwise; the LOD cut's figures only where they were
// measured, so they read back as NaN, not measured, when they were not).
// cell_from_json throws nlohmann::json::exception on a malformed object.
nlohmann::json to_json(const VerifyViewResult& view);
nlohmann::json to_json(const VerifyCellResult& cell);
VerifyCellResult cell_from_json(const nlohmann::json& j);

// The `summary` object of report.json: cells, cells_failed, views,
// truth_blank_views (views whose truth was blank: their PSNR says nothing), and per
// metric of verify_metrics() {count, median, worst, worst_cell, worst_view (over
// the random views), median_centre, median_corner, median_sample,
// median_reference}; also median bake seconds and bytes per cell.
nlohmann::json summary_json(const std::vector<VerifyCellResult>& cells);

struct VerifyReportInput {
  std::string database;                 // shown in the report
  nlohmann::json params;                // the verify parameters, shown and stored
  std::vector<VerifyCellResult> cells;  // in id order
  int worst_views = 6;     // triptychs shown (cells with the worst views)
  InputFiles inputs;       // the files verify read (database, store): no report file may be one of them
  std::optional<VerifyWalkSection> walk;  // `verify --walk-seconds`: its section and report.json "walk"
};

// The report's absolute colour scale for a cell's median PSNR, dB: at or below
// kVerifyPsnrRed red, at or above kVerifyPsnrGreen green, yellow half way;
// PSNR = inf (impostor equal to the truth) is "perfect".
inline constexpr double kVerifyPsnrRed = 20, kVerifyPsnrGreen = 40;

struct VerifyReportFiles {
  std::filesystem::path html, json;
  std::vector<std::filesystem::path> plots;  // SVG files
  std::filesystem::path cell_map;            // SVG
};

// Writes into `dir` (created): report.json ({database, params, summary, cells}),
// plots/*.svg (median PSNR per cell vs bake seconds, vs triangles drawn, vs
// stored bytes; PSNR and hole fraction per view vs distance from the sample
// point), cell_map.svg (cell footprints coloured by median PSNR) and
// report.html, self-contained (inline CSS, the cell map and plots as inline
// SVG so their tooltips work, the triptych PNGs as data: URIs), so it can be
// copied or mailed alone. The triptych PNGs named by the cells must already be
// in `dir` (one that cannot be read is left out). Throws
// std::runtime_error naming a file that cannot be written.
VerifyReportFiles write_verify_report(const std::filesystem::path& dir, const VerifyReportInput& input);

// Writes `text` to `file` through an OutputFile: a temporary file and a rename
// (readers never see half a file), never over a database or one of `inputs`.
// Throws std::runtime_error naming the file.
void write_text_file_atomically(const std::filesystem::path& file, const std::string& text,
                                const InputFiles& inputs);

}  // namespace cellbake
