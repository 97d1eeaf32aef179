// `cellbake render DB --eye X,Y,Z --look X,Y,Z [--fov DEG] [--size WxH]
//  [--mode impostor|truth|diff] [--cell ID] --out FILE.png [--json] [--path FILE]`:
// headless rendering of a view cell's impostor, the ground truth, or their
// false-colour difference with error metrics (docs/viewer.md). Given a
// geometry store instead, it renders the model's ground truth (a look before
// baking), by default from outside its bounds looking at its centre.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "runner/commands.h"
#include "storage/database_kind.h"
#include "storage/output_file.h"
#include "viewer/camera_path.h"
#include "viewer/sample_selection.h"
#include "viewer/png_file.h"
#include "viewer/view_session.h"

namespace cellbake {
namespace {

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json result_json(const ViewResult& r) {
  nlohmann::json j;
  j["cell_id"] = r.cell_id;
  j["fallback"] = r.fallback;
  if (r.fallback) j["fallback_reason"] = r.fallback_reason;
  j["triangles_impostor"] = r.triangles_impostor;
  j["triangles_truth"] = r.triangles_truth;
  j["ms_impostor"] = r.impostor ? nlohmann::json(r.impostor_stats.milliseconds) : nlohmann::json(nullptr);
  j["ms_truth"] = r.truth ? nlohmann::json(r.truth_stats.milliseconds) : nlohmann::json(nullptr);
  if (r.metrics) {
    j["psnr_db"] = finite_or_null(r.metrics->psnr_db);
    j["ssim"] = r.metrics->ssim;
    j["hole_fraction"] = r.metrics->hole_fraction;
    j["skin_fraction"] = r.metrics->skin_fraction;
    j["extra_fraction"] = r.metrics->extra_fraction;
    j["depth_error_median"] = r.metrics->depth_error_median;
  }
  return j;
}

void print_result(const ViewResult& r, const std::filesystem::path& out) {
  std::printf("%s: cell %lld%s\n", out.c_str(), (long long)r.cell_id, r.fallback ? " (fallback: ground truth)" : "");
  if (r.impostor)
    std::printf("  impostor: %llu triangles, %.2f ms\n", (unsigned long long)r.triangles_impostor,
                r.impostor_stats.milliseconds);
  if (r.truth)
    std::printf("  truth:    %llu triangles, %.2f ms\n", (unsigned long long)r.triangles_truth,
                r.truth_stats.milliseconds);
  if (r.metrics)
    std::printf("  PSNR %.2f dB, SSIM %.4f, holes %.4f, skins %.4f, extra %.4f, median depth error %.5f\n",
                r.metrics->psnr_db, r.metrics->ssim, r.metrics->hole_fraction, r.metrics->skin_fraction,
                r.metrics->extra_fraction, r.metrics->depth_error_median);
}

// Writes the image `mode` names to `out` (never over a database or one of `inputs`).
void write_result_image(const ViewResult& r, ViewMode mode, const std::filesystem::path& out,
                        const InputFiles& inputs) {
  if (mode == ViewMode::diff) {
    write_png(out, r.truth->width, r.truth->height, error_image(*r.impostor, *r.truth), inputs);
  } else {
    const ViewFrame& f = mode == ViewMode::truth ? *r.truth : *r.impostor;
    write_png(out, f.width, f.height, f.color, inputs);
  }
}

// The files a render reads: no output may be one of them.
InputFiles render_inputs(const ViewSession& session, const std::string& database, const std::string& path) {
  InputFiles inputs{database, session.store().path()};
  if (!path.empty()) inputs.push_back(path);
  return inputs;
}

std::string csv_number(double v) {
  if (!std::isfinite(v)) return "inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

struct Options {
  std::string database, eye, look, size = "512x512", mode = "impostor", out, path, store;
  double fov = 60, near = 0.05;
  std::int64_t cell = 0;
  bool json = false;
  std::optional<std::uint64_t> far_budget;
  int max_samples = 0;
};

// `render STORE.db`: the ground truth of a geometry store, one view (eye and
// look default to default_overview's), written to --out.
void render_store(const Options& opt, bool mode_given) {
  if (mode_given && opt.mode != "truth")
    throw std::invalid_argument(opt.database + " is a geometry store (not baked): only --mode truth can be drawn");
  if (!opt.path.empty()) throw std::invalid_argument("--path needs a cell database; " + opt.database + " is a geometry store");
  ViewSession session(StoreOnly{}, opt.database);
  const InputFiles inputs = render_inputs(session, opt.database, opt.path);
  check_output_target(opt.out, inputs);  // before the drawing
  ViewRequest request;
  default_overview(session.store().model_bounds(), session.up(), request);
  if (!opt.eye.empty()) request.eye = parse_point(opt.eye, "--eye");
  if (!opt.look.empty()) request.look = parse_point(opt.look, "--look");
  const auto [width, height] = parse_image_size(opt.size);
  request.width = width, request.height = height;
  request.fov_y_deg = opt.fov;
  request.near_plane = opt.near;
  const ViewResult r = session.render(request, ViewMode::truth, stderr);
  write_result_image(r, ViewMode::truth, opt.out, inputs);
  if (opt.json) {
    nlohmann::json j = result_json(r);
    j["eye"] = {request.eye.x, request.eye.y, request.eye.z};
    j["look"] = {request.look.x, request.look.y, request.look.z};
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s: ground truth of geometry store %s from eye %.6g,%.6g,%.6g looking at %.6g,%.6g,%.6g\n",
                opt.out.c_str(), opt.database.c_str(), request.eye.x, request.eye.y, request.eye.z, request.look.x,
                request.look.y, request.look.z);
    std::printf("  truth:    %llu triangles, %.2f ms\n", (unsigned long long)r.triangles_truth,
                r.truth_stats.milliseconds);
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "render", "Render a view headless: a cell's impostor, the ground truth, or their difference with metrics");
  cmd->add_option("database", opt->database,
                  "Cell database, or a geometry store (ground truth only: a look at the model before baking)")
      ->required();
  cmd->add_option("--eye", opt->eye,
                  "Eye position X,Y,Z (model units); on a geometry store default: outside the model's bounds");
  cmd->add_option("--look", opt->look, "Point looked at X,Y,Z; on a geometry store default: the model's centre");
  cmd->add_option("--fov", opt->fov, "Vertical field of view, degrees")
      ->check(CLI::Range(1.0, 179.0))
      ->capture_default_str();
  cmd->add_option("--size", opt->size, "Image size WxH")->capture_default_str();
  cmd->add_option("--mode", opt->mode,
                  "impostor | truth | diff (false-colour error image + metrics); a geometry store: truth only")
      ->check(CLI::IsMember({"impostor", "truth", "diff"}))
      ->capture_default_str();
  cmd->add_option("--cell", opt->cell, "Use this cell's impostor instead of the eye's cell");
  cmd->add_option("--near", opt->near, "Near plane distance, model units")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--store", opt->store, "Geometry store (default: the one the database names)");
  cmd->add_option("--out", opt->out, "Output PNG (with --path: the base name of OUT_0000.png ... and OUT.csv)")
      ->required();
  cmd->add_flag("--json", opt->json, "Print the result as JSON");
  cmd->add_option("--far-budget", opt->far_budget,
                  "Far-field triangles per view: the nearest sample with its ancestors, then more samples while "
                  "under this (default: the bake's view.far_budget)");
  cmd->add_option("--max-samples", opt->max_samples,
                  "At most this many samples (0 = no cap; 1 = the root sample alone: the single-sample far field)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--path", opt->path, "Camera path file: one view per line, \"ex ey ez lx ly lz\"");
  cmd->callback([cmd, opt] {
    if (database_kind(opt->database) == DatabaseKind::geometry_store) {
      render_store(*opt, cmd->count("--mode") > 0);
      return;
    }
    std::vector<PathView> views;
    if (!opt->path.empty()) {
      views = read_camera_path(opt->path);
    } else {
      if (opt->eye.empty() || opt->look.empty()) throw std::invalid_argument("--eye and --look are needed without --path");
      views.push_back({parse_point(opt->eye, "--eye"), parse_point(opt->look, "--look")});
    }
    const auto [width, height] = parse_image_size(opt->size);
    const ViewMode mode = parse_view_mode(opt->mode);
    ViewSession session(opt->database, opt->store);
    const InputFiles inputs = render_inputs(session, opt->database, opt->path);
    if (const std::string mismatch = session.store_mismatch(); !mismatch.empty())
      std::fprintf(stderr, "warning: %s\n", mismatch.c_str());
    ViewRequest request;
    request.fov_y_deg = opt->fov;
    request.width = width;
    request.height = height;
    request.near_plane = opt->near;
    request.far_budget = opt->far_budget;
    request.max_samples = opt->max_samples;
    if (opt->cell != 0) request.cell = opt->cell;

    if (opt->path.empty()) {
      check_output_target(opt->out, inputs);  // before the drawing
      request.eye = views[0].eye;
      request.look = views[0].look;
      const ViewResult r = session.render(request, mode, stderr);
      write_result_image(r, mode, opt->out, inputs);
      if (opt->json)
        std::printf("%s\n", result_json(r).dump(2).c_str());
      else
        print_result(r, opt->out);
      return;
    }

    // A path: every frame gets the impostor, the truth and the metrics; the
    // image written is the one --mode names.
    const std::filesystem::path base = opt->out;
    const std::filesystem::path csv_path = base.parent_path() / (base.stem().string() + ".csv");
    check_output_target(csv_path, inputs);  // before the drawing
    for (std::size_t i = 0; i < views.size(); ++i)
      check_output_target(numbered_path(base, static_cast<int>(i)), inputs);
    std::ostringstream csv;  // written whole at the end
    csv << "frame,image,cell_id,fallback,eye_x,eye_y,eye_z,psnr_db,ssim,hole_fraction,skin_fraction,extra_fraction,"
           "depth_error_median,triangles_impostor,triangles_truth,ms_impostor,ms_truth\n";
    nlohmann::json frames = nlohmann::json::array();
    for (std::size_t i = 0; i < views.size(); ++i) {
      request.eye = views[i].eye;
      request.look = views[i].look;
      const ViewResult r = session.render(request, ViewMode::diff, stderr);
      const std::filesystem::path image = numbered_path(base, static_cast<int>(i));
      write_result_image(r, mode, image, inputs);
      const ImageMetrics& m = *r.metrics;
      csv << i << "," << image.filename().string() << "," << r.cell_id << "," << (r.fallback ? 1 : 0) << ","
          << csv_number(request.eye.x) << "," << csv_number(request.eye.y) << "," << csv_number(request.eye.z) << ","
          << csv_number(m.psnr_db) << "," << csv_number(m.ssim) << "," << csv_number(m.hole_fraction) << ","
          << csv_number(m.skin_fraction) << "," << csv_number(m.extra_fraction) << ","
          << csv_number(m.depth_error_median) << "," << r.triangles_impostor << "," << r.triangles_truth << ","
          << csv_number(r.impostor_stats.milliseconds) << "," << csv_number(r.truth_stats.milliseconds) << "\n";
      if (opt->json) {
        nlohmann::json j = result_json(r);
        j["frame"] = i;
        j["image"] = image.string();
        frames.push_back(j);
      } else {
        print_result(r, image);
      }
    }
    write_output_file(csv_path, csv.str(), inputs);
    if (opt->json) std::printf("%s\n", nlohmann::json{{"frames", frames}, {"csv", csv_path.string()}}.dump(2).c_str());
    else std::printf("%zu frames, metrics in %s\n", views.size(), csv_path.c_str());
  });
}

}  // namespace cellbake
