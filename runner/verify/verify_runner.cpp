#include "runner/verify/verify_runner.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "pipeline/cell_grid.h"
#include "runner/progress.h"
#include "runner/verify/verify_report.h"
#include "runner/walk/walk_runner.h"
#include "stages/render/gl_context.h"
#include "stages/sample/sample_points.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "storage/store_check.h"
#include "storage/meta_values.h"
#include "viewer/baked_config_text.h"
#include "viewer/cell_index.h"
#include "viewer/decoded_cell.h"
#include "viewer/image_metrics.h"
#include "viewer/png_file.h"
#include "viewer/scene_drawer.h"
#include "viewer/triptych.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

// The light model the truth and the samples were drawn with, for the report:
// "unlit" or "lit: key (x y z) x s, fill (x y z) x s, ambient a" in world axes.
std::string describe_lighting(const ShadingLights& l) {
  if (!l.lit) return "unlit (colours as stored)";
  char text[256];
  std::snprintf(
      text, sizeof text,
      "lit, two-sided Lambert: key (%.3f %.3f %.3f) x %.2f, fill (%.3f %.3f %.3f) x %.2f, ambient %.2f",
      l.key.x, l.key.y, l.key.z, l.key_strength, l.fill.x, l.fill.y, l.fill.z, l.fill_strength, l.ambient);
  return text;
}

constexpr int kCacheVersion = 3;  // 2: views record truth_blank; 3: random views over the navigable part

// Where a cell's eyes may be: its bounds intersected with its region (the
// bounds alone when the database names no such region).
Box3d navigable_of(const CellRow& row, const std::vector<Box3d>& regions) {
  if (row.region < 0 || row.region >= int(regions.size())) return row.bounds;
  const Box3d part = navigable_part(row.bounds, regions[std::size_t(row.region)]);
  return part.empty() ? row.bounds : part;
}

struct CellTask {
  std::int64_t id = 0;
  std::string key;
};

// The resume file: results by cell id (empty when missing or unreadable).
std::map<std::int64_t, VerifyCellResult> load_cache(const std::filesystem::path& file) {
  std::map<std::int64_t, VerifyCellResult> cells;
  std::ifstream in(file);
  if (!in) return cells;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.value("version", 0) != kCacheVersion) return cells;
    for (const auto& c : j.at("cells")) {
      VerifyCellResult r = cell_from_json(c);
      cells[r.id] = std::move(r);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "note: ignoring %s (%s); every cell will be rendered\n", file.c_str(), e.what());
    cells.clear();
  }
  return cells;
}

// Writes `fresh` and, for cells it lacks, `older` (results of cells not selected this time are kept).
void save_cache(const std::filesystem::path& file, const std::map<std::int64_t, VerifyCellResult>& fresh,
                const std::map<std::int64_t, VerifyCellResult>& older, const InputFiles& inputs) {
  std::map<std::int64_t, const VerifyCellResult*> all;
  for (const auto& [id, c] : older) all[id] = &c;
  for (const auto& [id, c] : fresh) all[id] = &c;
  nlohmann::json j{{"version", kCacheVersion}, {"cells", nlohmann::json::array()}};
  for (const auto& [id, c] : all) j["cells"].push_back(to_json(*c));
  write_text_file_atomically(file, j.dump(), inputs);
}

// `--walk-seconds`: a walk through the selected cells into DIR/walk/ at the
// views' size, for the report; a walk that fails is reported, not fatal.
VerifyWalkSection verify_walk(const std::filesystem::path& database, const std::filesystem::path& report_dir,
                              const std::vector<CellSpec>& specs, const VerifyOptions& options) {
  VerifyWalkSection section;
  try {
    WalkOptions wo;
    wo.store = options.store;
    for (const CellSpec& s : specs) wo.cells += (wo.cells.empty() ? "" : ",") + std::to_string(s.id);
    wo.seconds = options.walk_seconds;
    wo.width = options.width;
    wo.height = options.height;
    wo.fov_y_deg = options.fov_y_deg;
    wo.near_plane = options.near_plane;
    wo.quiet = options.quiet;
    const WalkResult r = run_walk(database, report_dir / "walk", wo);
    const auto rel = [](const std::filesystem::path& p) { return p.empty() ? "" : "walk/" + p.filename().string(); };
    section.video = rel(r.video);
    section.frames_dir = rel(r.frames_dir);
    section.plot = rel(r.plot);
    section.worst_png = rel(r.worst_png);
    section.summary_text = walk_summary_text(r.summary);
    section.summary = walk_summary_json(r.summary);
  } catch (const std::exception& e) {
    section.error = e.what();
    std::fprintf(stderr, "warning: verify: the walk failed: %s\n", e.what());
  }
  return section;
}

}  // namespace

VerifySummary run_verify(const std::filesystem::path& database, const std::filesystem::path& report_dir,
                         const VerifyOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.views_per_cell < 1) throw std::invalid_argument("verify: --views-per-cell must be at least 1");
  if (options.width < 8 || options.height < 8)
    throw std::invalid_argument("verify: image size must be at least 8x8");
  if (options.supersample < 1 || options.supersample > 4)
    throw std::invalid_argument("verify: --supersample must be 1 to 4");
  const int threads =
      options.threads > 0 ? options.threads : int(std::max(1u, std::thread::hardware_concurrency()));
  if (!std::getenv("LP_NUM_THREADS")) setenv("LP_NUM_THREADS", threads > 1 ? "1" : "2", 1);

  CellDb db(database, CellDb::Mode::read_only);
  const auto store_meta = db.meta("store");
  if (options.store.empty() && !store_meta)
    throw std::runtime_error("verify: " + database.string() + " has no meta 'store' (not a cell database?)");
  const std::filesystem::path store_path = options.store.empty() ? std::filesystem::path(*store_meta) : options.store;
  require_sound_store(store_path, options.check_store);
  GeometryStore store(store_path);
  // Cells baked from another store name chunks of another model: nothing of them can be verified.
  if (const std::string mismatch = store_mismatch(database, db.meta("store_hash"), store_path, store.summary().content_hash);
      !mismatch.empty())
    throw std::runtime_error("verify: " + mismatch);
  const std::string up_name = db.meta("up").value_or("z");
  const Vec3d up = up_axis(up_name);
  meta_double(db, "cell_size", 0);  // not used here, but a damaged value fails the run naming the key
  const std::string config_text = db.meta("config").value_or("");
  const std::vector<Box3d> regions = regions_of_config_text(config_text);
  const ShadingLights shading = shading_lights(shading_of_config_text(config_text), up);
  const std::uint64_t far_budget = options.far_budget.value_or(
      far_budget_of_config_text(config_text).value_or(SampleSelectionParams{}.far_budget));

  nlohmann::json params{{"views_per_cell", options.views_per_cell},
                        {"width", options.width},
                        {"height", options.height},
                        {"fov_y_deg", options.fov_y_deg},
                        {"near_plane", options.near_plane},
                        {"seed", options.seed},
                        {"up", up_name},
                        {"store_hash", db.meta("store_hash").value_or("")},
                        {"far_budget", far_budget},
                        {"max_samples", options.max_samples},
                        {"sample_views", options.sample_views},
                        {"reference_views", options.reference_views},
                        {"far_budget_sweep", options.far_budget_sweep},
                        {"lighting", describe_lighting(shading)}};
  if (options.lod_cut) params["lod_cut"] = true;  // absent otherwise: earlier resume files stay valid
  if (options.supersample > 1) params["supersample"] = options.supersample;
  const std::string params_key = params.dump();

  // Selected done cells, in id order.
  const CellIndex index(db);
  std::vector<CellSpec> specs;
  for (const auto& e : index.cells())
    if (e.done) specs.push_back({e.id, 0, e.gx, e.gy, e.gz, e.bounds});
  const auto stamps = db.stamps();
  // Done cells whose rows CellIndex could not read: verified too, so they fail located in the report.
  for (const auto& [id, stamp] : stamps)
    if (!stamp.error.empty() && stamp.status == "done") specs.push_back({id, 0, 0, 0, 0, Box3d{}});
  std::sort(specs.begin(), specs.end(), [](const CellSpec& a, const CellSpec& b) { return a.id < b.id; });
  specs = select_cells(specs, options.cells);

  const InputFiles inputs{database, store.path()};  // no report file may be one of them
  std::filesystem::create_directories(report_dir / "views");
  const std::filesystem::path cache_file = report_dir / "verify-cells.json";
  std::map<std::int64_t, VerifyCellResult> cached = load_cache(cache_file);
  std::map<std::int64_t, VerifyCellResult> results;
  std::vector<CellTask> pending;
  VerifySummary summary;
  summary.cells_selected = specs.size();
  for (const auto& s : specs) {
    const auto stamp = stamps.find(s.id);
    const std::string key =
        (stamp != stamps.end() ? stamp->second.content_hash : std::string()) + "|" + params_key;
    auto it = cached.find(s.id);
    if (it != cached.end() && it->second.key == key && it->second.error.empty() &&
        (it->second.triptych.empty() || std::filesystem::exists(report_dir / it->second.triptych))) {
      results[s.id] = it->second;
      ++summary.cells_reused;
      continue;
    }
    pending.push_back({s.id, key});
  }

  std::mutex mutex;  // guards db, results, the cache file and the counters
  ProgressBar progress("verify", pending.size(), "cells");
  std::uint64_t done = 0;
  auto last_save = std::chrono::steady_clock::now();

  auto verify_cell = [&](const CellTask& task, std::unique_ptr<SceneDrawer>& drawer) {
    VerifyCellResult result;
    result.id = task.id;
    result.key = task.key;
    std::optional<CellRow> row;
    try {
      {
        std::lock_guard lock(mutex);
        row = db.get_cell(task.id, true);  // throws naming database and cell for an unreadable row
      }
      if (!row) throw std::runtime_error("cell " + std::to_string(task.id) + " is not in the database");
      result.bounds = row->bounds;
      result.bake_seconds = row->stage_seconds;
      result.bytes = row->bytes;
      for (const SampleRow& sample : row->samples)
        for (const FaceRow& face : sample.faces)
          result.colour_bytes += face.image.size(), result.mesh_bytes += face.mesh.size();
      result.near_list_bytes = pack_near_chunks(row->near_chunks).size();
      result.near_triangles = row->near_triangles;
      result.far_triangles = row->far_triangles;
      result.far_geometry_triangles = row->far_geometry_triangles;
      const DecodedCell cell = decode_cell(*row, &store);  // far pieces cut here, not timed as drawing
      const Box3d navigable = navigable_of(*row, regions);
      auto plans =
          plan_verify_views(row->bounds, navigable, up, options.views_per_cell, options.reference_views,
                            options.seed * 0x9E3779B97F4A7C15ull + std::uint64_t(task.id));
      for (const auto& s : row->samples) {
        result.void_curve.push_back(s.void_after);
        result.sample_seconds.push_back(s.seconds);
      }
      if (options.sample_views && row->samples.size() > 1) {
        // Look from each sample point too, along the golden-angle directions after the plans' own.
        const double reach = length(row->bounds.extent());
        for (const SampleRow& s : row->samples) {
          const Vec3d dir = golden_angle_direction(int(plans.size()), up);
          plans.push_back({VerifyViewKind::sample, s.eye, s.eye + dir * reach});
        }
      }
      if (!drawer) {
        SceneDrawerParams dp;
        dp.tdm_cache_bytes = std::size_t{256} << 20;
        drawer = std::make_unique<SceneDrawer>(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)),
                                               store, dp);
        drawer->set_shading(shading);  // the bake's light model: truth lit like the far field
      }
      SceneDrawOptions draw_options;
      draw_options.samples.far_budget = far_budget;
      draw_options.samples.max_samples = options.max_samples;
      SceneDrawOptions root_options = draw_options;
      root_options.samples.max_samples = 1;
      ViewFrame worst_truth, worst_impostor;
      // Frames are drawn at W x H (the image size times --supersample) and
      // box-filtered down to the image size.
      const int ss = options.supersample;
      const int W = options.width * ss, H = options.height * ss;
      const auto to_image_size = [ss](ViewFrame& frame) {
        if (ss > 1) frame = box_downsample(frame, ss);
      };
      for (const auto& plan : plans) {
        const RenderCamera camera =
            look_at_camera(plan.eye, plan.look, up, options.fov_y_deg, W, H, options.near_plane);
        ViewFrame impostor, truth, root;
        VerifyViewResult v;
        try {
          drawer->draw_impostor(camera, W, H, cell, draw_options,
                                impostor);  // uploads
          const SceneFrameStats is =
              drawer->draw_impostor(camera, W, H, cell, draw_options, impostor);
          if (cell.samples.size() > 1) {
            drawer->draw_impostor(camera, W, H, cell, root_options, root);
            to_image_size(root);
          }
          to_image_size(impostor);
          v.samples_drawn = is.samples_drawn;
          drawer->draw_truth(camera, W, H, draw_options, truth);  // uploads
          const SceneFrameStats ts =
              drawer->draw_truth(camera, W, H, draw_options, truth);
          to_image_size(truth);
          if (is_headline_view(plan.kind))  // speed against error: the same view under each swept budget
            for (const std::uint64_t budget : options.far_budget_sweep) {
              SceneDrawOptions swept = draw_options;
              swept.samples.far_budget = budget;
              ViewFrame frame;
              const SceneFrameStats st =
                  drawer->draw_impostor(camera, W, H, cell, swept, frame);
              to_image_size(frame);
              v.far_budget_sweep.push_back(
                  {budget, st.chunk_triangles + st.far_triangles, compare_frames(frame, truth).psnr_db});
            }
          if (options.lod_cut) {  // the yardstick: the model's chunk levels with the impostor's triangles, and at 1 px
            ViewFrame frame;
            LodCut cut;
            drawer->draw_lod_cut(camera, W, H, draw_options,
                                 std::max<std::uint64_t>(1, is.chunk_triangles + is.far_triangles), 0, frame, &cut);
            to_image_size(frame);
            v.psnr_db_cut = compare_frames(frame, truth).psnr_db;
            v.cut_error_px = cut.error_px / ss;  // in image pixels
            drawer->draw_lod_cut(camera, W, H, draw_options, 0, 1.0 * ss, frame, &cut);  // 1 image pixel
            to_image_size(frame);
            v.psnr_db_cut_1px = compare_frames(frame, truth).psnr_db;
            v.triangles_cut_1px = double(cut.triangles);
          }
          drawer->release_context();
          v.triangles_impostor =
              is.chunk_triangles + is.far_triangles;  // near + far geometry + depth meshes drawn
          v.triangles_truth = ts.chunk_triangles;
          if (v.triangles_truth > 0)
            v.triangle_ratio = double(v.triangles_impostor) / double(v.triangles_truth);
          v.ms_impostor = is.milliseconds;
          v.ms_truth = ts.milliseconds;
        } catch (...) {
          drawer->release_context();
          throw;
        }
        const ImageMetrics m = compare_frames(impostor, truth);
        const ImageMetrics mr = cell.samples.size() > 1 ? compare_frames(root, truth) : m;
        v.psnr_db_root = mr.psnr_db;
        v.hole_fraction_root = mr.hole_fraction;
        v.kind = plan.kind;
        v.eye = plan.eye;
        v.look = plan.look;
        v.distance_from_sample = std::numeric_limits<double>::infinity();
        for (const auto& s : row->samples)
          v.distance_from_sample = std::min(v.distance_from_sample, length(plan.eye - s.eye));
        v.psnr_db = m.psnr_db;
        v.psnr_gain_over_cut = psnr_difference(v.psnr_db, v.psnr_db_cut);
        v.ssim = m.ssim;
        v.hole_fraction = m.hole_fraction;
        v.skin_fraction = m.skin_fraction;
        v.extra_fraction = m.extra_fraction;
        v.depth_error_median = m.depth_error_median;
        v.truth_blank = is_blank(truth);
        result.views.push_back(v);
        // The cell's worst view, shown as its triptych (worst_view_index: of the random views, which come
        // first).
        if (worst_view_index(result.views) == int(result.views.size()) - 1) {
          result.worst_view = int(result.views.size()) - 1;
          worst_truth = std::move(truth);
          worst_impostor = std::move(impostor);
        }
      }
      if (result.worst_view >= 0) {
        result.triptych = "views/cell_" + std::to_string(task.id) + ".png";
        write_png(report_dir / result.triptych, 3 * options.width, options.height,
                  triptych(worst_truth, worst_impostor, error_image(worst_impostor, worst_truth)), inputs);
      }
    } catch (const std::exception& e) {
      result.views.clear();
      result.worst_view = -1;
      result.triptych.clear();
      const std::string what = e.what();  // located: database, cell, what
      result.error = what.rfind(database.string() + ": cell ", 0) == 0
                         ? what
                         : database.string() + ": cell " + std::to_string(task.id) + ": " + what;
    }
    std::lock_guard lock(mutex);
    if (!result.error.empty()) {
      ++summary.cells_failed;
      progress.line("warning: " + result.error);
    } else if (options.verbose) {
      std::vector<double> psnr;
      for (const VerifyViewResult& v : result.views)
        if (!v.truth_blank && is_headline_view(v.kind)) psnr.push_back(v.psnr_db);
      char line[160];
      std::snprintf(line, sizeof line,
                    "cell %lld: %zu views, median PSNR %.2f dB, worst %.2f dB (view %d) over random views",
                    (long long)result.id, result.views.size(), median_of(psnr),
                    result.worst_view >= 0 ? result.views[result.worst_view].psnr_db : 0.0,
                    result.worst_view);
      progress.line(line);
    }
    summary.views_rendered += result.views.size();
    results[task.id] = std::move(result);
    ++summary.cells_rendered;
    if (std::chrono::steady_clock::now() - last_save > std::chrono::seconds(2)) {
      save_cache(cache_file, results, cached, inputs);
      last_save = std::chrono::steady_clock::now();
    }
    if (!options.quiet) progress.update(++done);
  };

  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::enumerable_thread_specific<std::unique_ptr<SceneDrawer>> drawers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pending.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i != range.end(); ++i)
                          verify_cell(pending[i], drawers.local());
                      });
  });
  if (!options.quiet && !pending.empty()) progress.finish();
  save_cache(cache_file, results, cached, inputs);

  VerifyReportInput input;
  input.database = std::filesystem::absolute(database).string();
  input.params = params;
  input.worst_views = options.worst_views;
  input.inputs = inputs;
  for (auto& [id, r] : results) input.cells.push_back(r);
  if (options.walk_seconds > 0) input.walk = verify_walk(database, report_dir, specs, options);
  const VerifyReportFiles files = write_verify_report(report_dir, input);
  summary.report_html = files.html;
  summary.report_json = files.json;
  const MetricStats psnr = metric_stats(input.cells, verify_metrics()[0]);
  summary.psnr_median_db = psnr.median;
  summary.psnr_median_reference_db = psnr.median_reference;
  for (const auto& c : input.cells) {
    summary.views += c.views.size();
    for (const auto& v : c.views) {
      summary.truth_blank_views += v.truth_blank;
      summary.identical_views += !v.truth_blank && std::isinf(v.psnr_db) && v.psnr_db > 0;
    }
  }
  if (summary.truth_blank_views > 0)
    std::fprintf(
        stderr,
        "warning: %llu of %llu truth views are blank (nothing of the model in view, or one colour over "
        "every covered pixel: a black, unlit or untextured model?): PSNR/SSIM say nothing there\n",
        (unsigned long long)summary.truth_blank_views, (unsigned long long)summary.views);
  if (summary.identical_views > 0 && summary.identical_views + summary.truth_blank_views == summary.views)
    std::fprintf(
        stderr,
        "note: every view the cells drew equals the truth: what they see is drawn as exact geometry "
        "(far.choice \"cheapest\" took geometry where it costs no more triangles), so nothing was "
        "approximated and PSNR is infinite; bake with --set far.choice=tdm to measure the depth meshes\n");
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace cellbake
