// `cellbake verify`: renders every selected (done) cell's impostor and the
// ground truth from several viewpoints inside the cell (runner/verify/verify_views.h)
// in parallel (oneTBB, one headless GL context per worker thread, OSMesa or EGL, released after
// each view), compares them (viewer/image_metrics.h) and writes the report
// folder (runner/verify/verify_report.h). Resumable: per-cell results are kept in
// DIR/verify-cells.json keyed by the cell's content hash and the verify
// parameters, so a rerun renders only changed or missing cells.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace cellbake {

struct VerifyOptions {
  // Views at uniformly random points of each cell's navigable part, random
  // horizontal directions: the headline (runner/verify/verify_views.h).
  int views_per_cell = 4;
  std::string cells;              // selection like "1-10,15" ("" = all done cells)
  int width = 320, height = 240;  // image size, pixels
  double fov_y_deg = 60;
  double near_plane = 0.05;     // model units
  std::uint64_t seed = 1;       // random view points and directions
  int threads = 0;              // 0 = all cores
  int worst_views = 8;          // triptychs shown in the report
  std::filesystem::path store;  // geometry store override ("" = the database's meta `store`)
  bool check_store = false;     // the store's full check first (else its row counts; storage/store_check.h)
  bool quiet = false;           // no progress output
  bool verbose = false;         // a line per verified cell: views, median and worst PSNR
  // Far field drawn per view (viewer/sample_selection.h); every view is also
  // drawn with the root sample alone for the 1-sample columns.
  std::optional<std::uint64_t> far_budget;  // unset: the database's view.far_budget
  int max_samples = 0;                      // 0 = as many as the budget allows
  // Random views drawn once more per budget here (speed against error as a
  // curve, runner/verify/far_budget_sweep.h); empty: no sweep.
  std::vector<std::uint64_t> far_budget_sweep;
  bool sample_views = true;                 // also look from every sample point of the cell (reported apart)
  bool reference_views = true;              // also look from the centre and the corners (reported apart)
  // Also draw every view as a cut through the store's chunk levels
  // (stages/far/lod_cut.h) with the impostor's triangles and at 1 pixel of
  // error: the yardstick of the far field (VerifyViewResult::psnr_db_cut).
  bool lod_cut = false;
  // Every frame (truth, cells, cut) is drawn at this many times the image
  // size on each axis and box-filtered down before it is compared: sub-pixel
  // geometry (thin pipes) is measured by its coverage, not by which pixel
  // centres happen to hit it. 1: one ray per pixel, as the viewer draws.
  int supersample = 1;
  // A walk through the selected cells this many seconds long (runner/walk/walk_runner.h) into
  // DIR/walk/, shown in the report; 0: none (the CLI and the demo default to 8).
  double walk_seconds = 0;
};

struct VerifySummary {
  std::uint64_t cells_selected = 0;  // done cells selected
  std::uint64_t cells_rendered = 0;  // rendered in this run
  std::uint64_t cells_reused = 0;    // taken from verify-cells.json
  std::uint64_t cells_failed = 0;    // could not be decoded or drawn (listed in the report)
  std::uint64_t views_rendered = 0;
  std::uint64_t views = 0;  // in the report (rendered + reused)
  std::uint64_t truth_blank_views =
      0;  // of those, truth views that were blank (image_metrics.h is_blank): PSNR says nothing
  // Of those, views (truth not blank) the cells drew exactly: nothing approximated.
  std::uint64_t identical_views = 0;
  // Over the random views whose truth is not blank (+inf when all are identical; NaN without any).
  double psnr_median_db = 0;
  double psnr_median_reference_db = 0;  // the same over centre, corner and sample-point views
  std::filesystem::path report_html, report_json;
  double seconds = 0;
};

// Verifies `database` into the folder `report_dir` (created). Throws for setup
// errors (database or store cannot be opened, bad options); a cell that fails
// to decode or draw is recorded in the report and does not stop the others.
// The metrics do not depend on `threads`; the timings do.
VerifySummary run_verify(const std::filesystem::path& database, const std::filesystem::path& report_dir,
                         const VerifyOptions& options);

}  // namespace cellbake
