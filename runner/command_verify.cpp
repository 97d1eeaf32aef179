// `cellbake verify DB [--views-per-cell N] [--cells SEL] [--size WxH]
//  [--threads N] [--walk-seconds N] --report DIR`: renders each cell's impostor against the ground
// truth from viewpoints inside the cell and writes DIR/report.html +
// DIR/report.json (runner/verify/verify_runner.h). Also registers its helper
// `cellbake plot CSV --x COL --y COL [--series COL] --out FILE.svg` (the
// report's SVG scatter plot over any CSV; scripts/sweep.sh uses it).
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "runner/commands.h"
#include "runner/console.h"
#include "runner/verify/svg_plot.h"
#include "runner/verify/verify_report.h"
#include "runner/verify/verify_runner.h"
#include "viewer/camera_path.h"

namespace cellbake {

void add_verify_command(CLI::App& app) {
  struct Options {
    std::string database, report, size = "320x240", sweep;
    bool json = false;
    VerifyOptions verify;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("verify",
                                     "Render every cell's impostor against the ground truth from views "
                                     "inside the cell; write an HTML/JSON report");
  cmd->add_option("database", opt->database, "Cell database")->required();
  cmd->add_option("--report", opt->report, "Report folder (report.html, report.json, plots, resume file)")
      ->required();
  cmd->add_option("--views-per-cell", opt->verify.views_per_cell,
                  "Random views per cell (the headline): eyes uniform over the cell's navigable part, random "
                  "horizontal directions; the centre, the corners and each sample point add reference views, "
                  "reported apart")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--cells", opt->verify.cells, "Cell selection, e.g. 1-10,15 (default: all done cells)");
  cmd->add_option("--size", opt->size, "Image size WxH")->capture_default_str();
  cmd->add_option("--fov", opt->verify.fov_y_deg, "Vertical field of view, degrees")
      ->check(CLI::Range(1.0, 179.0));
  cmd->add_option("--near", opt->verify.near_plane, "Near plane distance, model units")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", opt->verify.seed, "Seed of the random views")->capture_default_str();
  cmd->add_flag("--no-reference-views{false}", opt->verify.reference_views,
                "Look only from the random views and the sample points, not from the centre and the corners");
  cmd->add_flag("--no-sample-views{false}", opt->verify.sample_views,
                "Do not look from the cell's sample points");
  cmd->add_flag("--lod-cut", opt->verify.lod_cut,
                "Also draw each view as a cut through the store's chunk levels with the cell's triangles, and "
                "at 1 px of error (the far field's yardstick: psnr_db_cut, psnr_gain_over_cut)");
  cmd->add_option("--supersample", opt->verify.supersample,
                  "Draw every frame at this many times the size on each axis and box-filter it down before "
                  "comparing (sub-pixel geometry measured by coverage, not by the pixel centres it happens to hit)")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  cmd->add_option("--threads", opt->verify.threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--worst", opt->verify.worst_views, "Worst views shown as triptychs")
      ->capture_default_str();
  cmd->add_option("--store", opt->verify.store, "Geometry store (default: the one the database names)");
  cmd->add_flag("--check-store", opt->verify.check_store,
                "Check the geometry store fully first (content hash recomputed, R-tree, every chunk decoded); by "
                "default only its row counts are compared with what ingest recorded");
  cmd->add_flag("--json", opt->json,
                "Print the summary as JSON (progress still goes to stderr; -q hides it)");
  cmd->add_option(
      "--far-budget", opt->verify.far_budget,
      "Far-field triangles per view: the nearest sample with its ancestors, then more while under this "
      "(default: the bake's view.far_budget)");
  cmd->add_option("--far-budget-sweep", opt->sweep,
                  "Speed against error as a curve: draw every random view once more per far budget in this "
                  "comma-separated list (e.g. 25000,50000,100000,200000,400000); the report plots median PSNR "
                  "against triangles drawn");
  cmd->add_option("--max-samples", opt->verify.max_samples,
                  "At most this many samples per view (0 = no cap; 1 = the root sample alone, the "
                  "single-sample far field)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  opt->verify.walk_seconds = 8;
  cmd->add_option("--walk-seconds", opt->verify.walk_seconds,
                  "A walk this long through the verified cells (truth | cells | difference video, plot of PSNR and "
                  "frame time; as `cellbake walk`) into DIR/walk/, shown in the report; 0: none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([opt] {
    std::tie(opt->verify.width, opt->verify.height) = parse_image_size(opt->size);
    if (!opt->sweep.empty()) opt->verify.far_budget_sweep = parse_far_budget_sweep(opt->sweep);
    opt->verify.quiet = quiet_output();
    opt->verify.verbose = verbose_output();
    const VerifySummary s = run_verify(opt->database, opt->report, opt->verify);
    if (opt->json) {
      const auto number = [](double v) {
        return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
      };
      const nlohmann::json j{{"database", opt->database},
                             {"cells_selected", s.cells_selected},
                             {"cells_rendered", s.cells_rendered},
                             {"cells_reused", s.cells_reused},
                             {"cells_failed", s.cells_failed},
                             {"views", s.views},
                             {"views_rendered", s.views_rendered},
                             {"truth_blank_views", s.truth_blank_views},
                             {"identical_views", s.identical_views},
                             {"psnr_median_db", number(s.psnr_median_db)},
                             {"psnr_median_reference_db", number(s.psnr_median_reference_db)},
                             {"psnr_median_infinite", std::isinf(s.psnr_median_db)},
                             {"seconds", s.seconds},
                             {"report_html", s.report_html.string()},
                             {"report_json", s.report_json.string()}};
      std::printf("%s\n", j.dump(2).c_str());
      if (s.cells_failed > 0)
        throw std::runtime_error(std::to_string(s.cells_failed) + " cell(s) could not be verified");
      return;
    }
    std::string blank;  // " (what the median does not say)"
    if (s.truth_blank_views > 0)
      blank = std::to_string(s.truth_blank_views) + " of " + std::to_string(s.views) +
              " truth views blank: single colour or empty, PSNR says nothing there";
    if (s.identical_views > 0)
      blank += (blank.empty() ? "" : "; ") + std::to_string(s.identical_views) + " of " +
               std::to_string(s.views) + " views identical to the truth: drawn as exact geometry";
    if (!blank.empty()) blank = " (" + blank + ")";
    char median[64];
    if (std::isnan(s.psnr_median_db))
      std::snprintf(median, sizeof median, "none (no view with the model in it)");
    else
      std::snprintf(median, sizeof median, "%.2f dB over random views", s.psnr_median_db);
    char reference[64] = "";
    if (!std::isnan(s.psnr_median_reference_db))
      std::snprintf(reference, sizeof reference, " (%.2f dB at the centre, corners and sample points)",
                    s.psnr_median_reference_db);
    std::printf(
        "verified %llu cells (%llu rendered, %llu reused, %llu failed), %llu views in %.1f s; median PSNR "
        "%s%s%s\n",
        (unsigned long long)s.cells_selected, (unsigned long long)s.cells_rendered,
        (unsigned long long)s.cells_reused, (unsigned long long)s.cells_failed,
        (unsigned long long)s.views_rendered, s.seconds, median, reference, blank.c_str());
    std::printf("report: %s\n", s.report_html.c_str());
    if (s.cells_failed > 0)
      throw std::runtime_error(std::to_string(s.cells_failed) + " cell(s) could not be verified");
  });

  struct PlotOptions {
    std::string csv, x, y, series, label, title, out;
    bool log_x = false;
  };
  auto plot = std::make_shared<PlotOptions>();
  CLI::App* pc =
      app.add_subcommand("plot", "Scatter plot of two CSV columns as SVG (the verify report's plot writer)");
  pc->add_option("csv", plot->csv, "CSV file with a header line")->required();
  pc->add_option("--x", plot->x, "Column for x")->required();
  pc->add_option("--y", plot->y, "Column for y")->required();
  pc->add_option("--series", plot->series, "Column whose values split the points into coloured series");
  pc->add_option("--label", plot->label, "Column used as each point's tooltip");
  pc->add_option("--title", plot->title, "Plot title");
  pc->add_flag("--log-x", plot->log_x, "Logarithmic x axis");
  pc->add_option("--out", plot->out, "Output SVG file")->required();
  pc->callback([plot] {
    std::ifstream in(plot->csv);
    if (!in) throw std::runtime_error("cannot read " + plot->csv);
    std::stringstream text;
    text << in.rdbuf();
    ScatterPlot p = scatter_plot_from_csv(text.str(), plot->x, plot->y, plot->series, plot->label);
    p.title = plot->title.empty() ? plot->y + " vs " + plot->x : plot->title;
    p.log_x = plot->log_x;
    write_text_file_atomically(plot->out, scatter_plot_svg(p), {plot->csv});
    std::printf("%s: %zu points\n", plot->out.c_str(), drawable_points(p));
  });
}

}  // namespace cellbake
