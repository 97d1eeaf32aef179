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
#include "runner/parallel.h"
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

// The options' limits (views per cell, image size, supersampling); throws naming the one broken.
void check_verify_options(const VerifyOptions& options) {
  if (options.views_per_cell < 1) throw std::invalid_argument("verify: --views-per-cell must be at least 1");
  if (options.width < 8 || options.height < 8)
    throw std::invalid_argument("verify: image size must be at least 8x8");
  if (options.supersample < 1 || options.supersample > 4)
    throw std::invalid_argument("verify: --supersample must be 1 to 4");
}

// The geometry store to draw the truth from: --store, else the database's meta 'store'.
std::filesystem::path verify_store_path(const CellDb& db, const std::filesystem::path& database,
                                        const VerifyOptions& options) {
  const auto store_meta = db.meta("store");
  if (options.store.empty() && !store_meta)
    throw std::runtime_error("verify: " + database.string() + " has no meta 'store' (not a cell database?)");
  return options.store.empty() ? std::filesystem::path(*store_meta) : options.store;
}

// What the cell database says about how its cells were baked: the up axis, the
// regions, the light model and the far budget (--far-budget overrides it).
struct BakedFacts {
  std::string up_name;
  Vec3d up;
  std::vector<Box3d> regions;
  ShadingLights shading;
  std::uint64_t far_budget = 0;
};

// Reads them from the database's meta; a damaged cell_size fails the run naming the key.
BakedFacts read_baked_facts(const CellDb& db, const VerifyOptions& options) {
  BakedFacts facts;
  facts.up_name = db.meta("up").value_or("z");
  facts.up = up_axis(facts.up_name);
  meta_double(db, "cell_size", 0);  // not used here, but a damaged value fails the run naming the key
  const std::string config_text = db.meta("config").value_or("");
  facts.regions = regions_of_config_text(config_text);
  facts.shading = shading_lights(shading_of_config_text(config_text), facts.up);
  facts.far_budget = options.far_budget.value_or(
      far_budget_of_config_text(config_text).value_or(SampleSelectionParams{}.far_budget));
  return facts;
}

// The verify parameters, shown in the report and part of each cached result's key.
nlohmann::json verify_params(const VerifyOptions& options, const BakedFacts& facts, const CellDb& db) {
  nlohmann::json params{{"views_per_cell", options.views_per_cell},
                        {"width", options.width},
                        {"height", options.height},
                        {"fov_y_deg", options.fov_y_deg},
                        {"near_plane", options.near_plane},
                        {"seed", options.seed},
                        {"up", facts.up_name},
                        {"store_hash", db.meta("store_hash").value_or("")},
                        {"far_budget", facts.far_budget},
                        {"max_samples", options.max_samples},
                        {"sample_views", options.sample_views},
                        {"reference_views", options.reference_views},
                        {"far_budget_sweep", options.far_budget_sweep},
                        {"lighting", describe_lighting(facts.shading)}};
  if (options.lod_cut) params["lod_cut"] = true;  // absent otherwise: earlier resume files stay valid
  if (options.supersample > 1) params["supersample"] = options.supersample;
  return params;
}

// The selected done cells in id order, and every row's stamp.
struct SelectedCells {
  std::vector<CellSpec> specs;
  std::map<std::int64_t, CellStamp> stamps;
};

// The done cells CellIndex reads, and the done rows it cannot read (so they
// fail located in the report), narrowed to --cells.
SelectedCells select_done_cells(const CellDb& db, const std::string& selection) {
  SelectedCells selected;
  std::vector<CellSpec>& specs = selected.specs;
  const CellIndex index(db);
  for (const auto& e : index.cells())
    if (e.done) specs.push_back({e.id, 0, e.gx, e.gy, e.gz, e.bounds});
  selected.stamps = db.stamps();
  // Done cells whose rows CellIndex could not read: verified too, so they fail located in the report.
  for (const auto& [id, stamp] : selected.stamps)
    if (!stamp.error.empty() && stamp.status == "done") specs.push_back({id, 0, 0, 0, 0, Box3d{}});
  std::sort(specs.begin(), specs.end(), [](const CellSpec& a, const CellSpec& b) { return a.id < b.id; });
  specs = select_cells(specs, selection);
  return selected;
}

// The selected cells still to render. A cached result is reused instead (kept
// with the results, counted) when its key (the cell's content hash and the
// parameters) still matches, it did not fail, and its triptych is still there.
std::vector<CellTask> pending_cells(const SelectedCells& selected, const std::string& params_key,
                                    const std::map<std::int64_t, VerifyCellResult>& cached,
                                    const std::filesystem::path& report_dir,
                                    std::map<std::int64_t, VerifyCellResult>& results, VerifySummary& summary) {
  std::vector<CellTask> pending;
  for (const auto& s : selected.specs) {
    const auto stamp = selected.stamps.find(s.id);
    const std::string key =
        (stamp != selected.stamps.end() ? stamp->second.content_hash : std::string()) + "|" + params_key;
    auto it = cached.find(s.id);
    if (it != cached.end() && it->second.key == key && it->second.error.empty() &&
        (it->second.triptych.empty() || std::filesystem::exists(report_dir / it->second.triptych))) {
      results[s.id] = it->second;
      ++summary.cells_reused;
      continue;
    }
    pending.push_back({s.id, key});
  }
  return pending;
}

// What the worker threads share while they verify cells: the inputs, and
// (under `mutex`) the database, the results, the resume file and the counters.
struct VerifyContext {
  const std::filesystem::path& database;
  const std::filesystem::path& report_dir;
  const VerifyOptions& options;
  const CellDb& db;
  const GeometryStore& store;
  const BakedFacts& facts;
  const InputFiles& inputs;
  const std::filesystem::path& cache_file;
  const std::map<std::int64_t, VerifyCellResult>& cached;  // kept in the resume file for cells not rendered now
  std::map<std::int64_t, VerifyCellResult>& results;
  VerifySummary& summary;
  ProgressBar& progress;
  std::mutex mutex{};  // guards db, results, the cache file and the counters
  std::uint64_t done = 0;
  std::chrono::steady_clock::time_point last_save = std::chrono::steady_clock::now();
};

// The stored row's figures the report shows beside the views: bounds, bake
// seconds, bytes by kind, triangles.
void copy_row_figures(const CellRow& row, VerifyCellResult& result) {
  result.bounds = row.bounds;
  result.bake_seconds = row.stage_seconds;
  result.bytes = row.bytes;
  for (const SampleRow& sample : row.samples)
    for (const FaceRow& face : sample.faces)
      result.colour_bytes += face.image.size(), result.mesh_bytes += face.mesh.size();
  result.near_list_bytes = pack_near_chunks(row.near_chunks).size();
  result.near_triangles = row.near_triangles;
  result.far_triangles = row.far_triangles;
  result.far_geometry_triangles = row.far_geometry_triangles;
}

// The views of a cell: random and reference views over its navigable part,
// then with --sample-views (and more than one sample) one from each sample
// point, along the golden-angle directions after the plans' own.
std::vector<VerifyViewPlan> plan_cell_views(const CellRow& row, std::int64_t id, const BakedFacts& facts,
                                            const VerifyOptions& options) {
  const Box3d navigable = navigable_of(row, facts.regions);
  auto plans = plan_verify_views(row.bounds, navigable, facts.up, options.views_per_cell, options.reference_views,
                                 options.seed * 0x9E3779B97F4A7C15ull + std::uint64_t(id));
  if (options.sample_views && row.samples.size() > 1) {
    const double reach = length(row.bounds.extent());
    for (const SampleRow& s : row.samples) {
      const Vec3d dir = golden_angle_direction(int(plans.size()), facts.up);
      plans.push_back({VerifyViewKind::sample, s.eye, s.eye + dir * reach});
    }
  }
  return plans;
}

// This worker's drawer, made on first use with the bake's light model (the
// truth lit like the far field).
void ensure_drawer(std::unique_ptr<SceneDrawer>& drawer, const GeometryStore& store, const ShadingLights& shading) {
  if (drawer) return;
  SceneDrawerParams dp;
  dp.tdm_cache_bytes = std::size_t{256} << 20;
  drawer = std::make_unique<SceneDrawer>(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), store, dp);
  drawer->set_shading(shading);
}

// How a cell's views are drawn: frames at W x H (the image size times
// --supersample, box-filtered down to the image size), the impostor with the
// far budget and sample cap, its root sample alone with root_options.
struct ViewDrawing {
  SceneDrawOptions options, root_options;
  int ss = 1, W = 0, H = 0;

  // A frame drawn at W x H brought down to the image size.
  void to_image_size(ViewFrame& frame) const {
    if (ss > 1) frame = box_downsample(frame, ss);
  }
};

// The drawing of a cell's views under the options and the far budget.
ViewDrawing view_drawing(const VerifyOptions& options, std::uint64_t far_budget) {
  ViewDrawing d;
  d.options.samples.far_budget = far_budget;
  d.options.samples.max_samples = options.max_samples;
  d.root_options = d.options;
  d.root_options.samples.max_samples = 1;
  d.ss = options.supersample;
  d.W = options.width * d.ss, d.H = options.height * d.ss;
  return d;
}

// The frames of one view, at the image size.
struct ViewFrames {
  ViewFrame impostor, truth, root;  // root: drawn only for cells with more than one sample
};

// Speed against error (--far-budget-sweep): the same view's impostor under each swept budget.
void sweep_far_budgets(SceneDrawer& drawer, const RenderCamera& camera, const DecodedCell& cell,
                       const ViewDrawing& d, const std::vector<std::uint64_t>& budgets, const ViewFrame& truth,
                       VerifyViewResult& v) {
  for (const std::uint64_t budget : budgets) {
    SceneDrawOptions swept = d.options;
    swept.samples.far_budget = budget;
    ViewFrame frame;
    const SceneFrameStats st = drawer.draw_impostor(camera, d.W, d.H, cell, swept, frame);
    d.to_image_size(frame);
    v.far_budget_sweep.push_back({budget, st.chunk_triangles + st.far_triangles, compare_frames(frame, truth).psnr_db});
  }
}

// The yardstick (--lod-cut): the model's chunk levels with the impostor's
// triangles, and at 1 image pixel of error.
void measure_lod_cut(SceneDrawer& drawer, const RenderCamera& camera, const ViewDrawing& d,
                     std::uint64_t impostor_triangles, const ViewFrame& truth, VerifyViewResult& v) {
  ViewFrame frame;
  LodCut cut;
  drawer.draw_lod_cut(camera, d.W, d.H, d.options, std::max<std::uint64_t>(1, impostor_triangles), 0, frame, &cut);
  d.to_image_size(frame);
  v.psnr_db_cut = compare_frames(frame, truth).psnr_db;
  v.cut_error_px = cut.error_px / d.ss;  // in image pixels
  drawer.draw_lod_cut(camera, d.W, d.H, d.options, 0, 1.0 * d.ss, frame, &cut);  // 1 image pixel
  d.to_image_size(frame);
  v.psnr_db_cut_1px = compare_frames(frame, truth).psnr_db;
  v.triangles_cut_1px = double(cut.triangles);
}

// Draws one view as the impostor (and its root sample alone), the truth and
// the optional sweep and LOD cut, into `frames`; the drawer's context is
// released whatever happens. Returns the view's draw counts and timings.
VerifyViewResult draw_view(SceneDrawer& drawer, const VerifyViewPlan& plan, const DecodedCell& cell,
                           const ViewDrawing& d, const VerifyOptions& options, const Vec3d& up, ViewFrames& frames) {
  const RenderCamera camera = look_at_camera(plan.eye, plan.look, up, options.fov_y_deg, d.W, d.H, options.near_plane);
  VerifyViewResult v;
  try {
    drawer.draw_impostor(camera, d.W, d.H, cell, d.options, frames.impostor);  // uploads
    const SceneFrameStats is = drawer.draw_impostor(camera, d.W, d.H, cell, d.options, frames.impostor);
    if (cell.samples.size() > 1) {
      drawer.draw_impostor(camera, d.W, d.H, cell, d.root_options, frames.root);
      d.to_image_size(frames.root);
    }
    d.to_image_size(frames.impostor);
    v.samples_drawn = is.samples_drawn;
    drawer.draw_truth(camera, d.W, d.H, d.options, frames.truth);  // uploads
    const SceneFrameStats ts = drawer.draw_truth(camera, d.W, d.H, d.options, frames.truth);
    d.to_image_size(frames.truth);
    if (is_headline_view(plan.kind)) sweep_far_budgets(drawer, camera, cell, d, options.far_budget_sweep, frames.truth, v);
    if (options.lod_cut) measure_lod_cut(drawer, camera, d, is.chunk_triangles + is.far_triangles, frames.truth, v);
    drawer.release_context();
    v.triangles_impostor = is.chunk_triangles + is.far_triangles;  // near + far geometry + depth meshes drawn
    v.triangles_truth = ts.chunk_triangles;
    if (v.triangles_truth > 0) v.triangle_ratio = double(v.triangles_impostor) / double(v.triangles_truth);
    v.ms_impostor = is.milliseconds;
    v.ms_truth = ts.milliseconds;
  } catch (...) {
    drawer.release_context();
    throw;
  }
  return v;
}

// The view's plan and its frames compared: PSNR, SSIM, holes, skins, extra
// surface, depth error (and the root sample's alone), the distance from the
// nearest sample point, a blank truth.
void compare_view(const VerifyViewPlan& plan, const CellRow& row, bool has_root, const ViewFrames& frames,
                  VerifyViewResult& v) {
  const ImageMetrics m = compare_frames(frames.impostor, frames.truth);
  const ImageMetrics mr = has_root ? compare_frames(frames.root, frames.truth) : m;
  v.psnr_db_root = mr.psnr_db;
  v.hole_fraction_root = mr.hole_fraction;
  v.kind = plan.kind;
  v.eye = plan.eye;
  v.look = plan.look;
  v.distance_from_sample = std::numeric_limits<double>::infinity();
  for (const auto& s : row.samples) v.distance_from_sample = std::min(v.distance_from_sample, length(plan.eye - s.eye));
  v.psnr_db = m.psnr_db;
  v.psnr_gain_over_cut = psnr_difference(v.psnr_db, v.psnr_db_cut);
  v.ssim = m.ssim;
  v.hole_fraction = m.hole_fraction;
  v.skin_fraction = m.skin_fraction;
  v.extra_fraction = m.extra_fraction;
  v.depth_error_median = m.depth_error_median;
  v.truth_blank = is_blank(frames.truth);
}

// Verifies one cell into `result`: its row read and decoded, every planned
// view drawn and compared, the worst view's triptych written. Throws on failure.
void measure_cell(VerifyContext& ctx, const CellTask& task, std::unique_ptr<SceneDrawer>& drawer,
                  VerifyCellResult& result) {
  std::optional<CellRow> row;
  {
    std::lock_guard lock(ctx.mutex);
    row = ctx.db.get_cell(task.id, true);  // throws naming database and cell for an unreadable row
  }
  if (!row) throw std::runtime_error("cell " + std::to_string(task.id) + " is not in the database");
  copy_row_figures(*row, result);
  const DecodedCell cell = decode_cell(*row, &ctx.store);  // far pieces cut here, not timed as drawing
  const std::vector<VerifyViewPlan> plans = plan_cell_views(*row, task.id, ctx.facts, ctx.options);
  for (const auto& s : row->samples) {
    result.void_curve.push_back(s.void_after);
    result.sample_seconds.push_back(s.seconds);
  }
  ensure_drawer(drawer, ctx.store, ctx.facts.shading);
  const ViewDrawing drawing = view_drawing(ctx.options, ctx.facts.far_budget);
  ViewFrame worst_truth, worst_impostor;
  for (const auto& plan : plans) {
    ViewFrames frames;
    VerifyViewResult v = draw_view(*drawer, plan, cell, drawing, ctx.options, ctx.facts.up, frames);
    compare_view(plan, *row, cell.samples.size() > 1, frames, v);
    result.views.push_back(v);
    // The cell's worst view, shown as its triptych (worst_view_index: of the random views, which come
    // first).
    if (worst_view_index(result.views) == int(result.views.size()) - 1) {
      result.worst_view = int(result.views.size()) - 1;
      worst_truth = std::move(frames.truth);
      worst_impostor = std::move(frames.impostor);
    }
  }
  if (result.worst_view >= 0) {
    result.triptych = "views/cell_" + std::to_string(task.id) + ".png";
    write_png(ctx.report_dir / result.triptych, 3 * ctx.options.width, ctx.options.height,
              triptych(worst_truth, worst_impostor, error_image(worst_impostor, worst_truth)), ctx.inputs);
  }
}

// Records a verified cell under the mutex: counted, its failure (or with
// --verbose its PSNR) printed, kept with the results, the resume file saved
// at most every 2 s, the progress advanced.
void record_cell(VerifyContext& ctx, const CellTask& task, VerifyCellResult result) {
  std::lock_guard lock(ctx.mutex);
  if (!result.error.empty()) {
    ++ctx.summary.cells_failed;
    ctx.progress.line("warning: " + result.error);
  } else if (ctx.options.verbose) {
    std::vector<double> psnr;
    for (const VerifyViewResult& v : result.views)
      if (!v.truth_blank && is_headline_view(v.kind)) psnr.push_back(v.psnr_db);
    char line[160];
    std::snprintf(line, sizeof line,
                  "cell %lld: %zu views, median PSNR %.2f dB, worst %.2f dB (view %d) over random views",
                  (long long)result.id, result.views.size(), median_of(psnr),
                  result.worst_view >= 0 ? result.views[result.worst_view].psnr_db : 0.0, result.worst_view);
    ctx.progress.line(line);
  }
  ctx.summary.views_rendered += result.views.size();
  ctx.results[task.id] = std::move(result);
  ++ctx.summary.cells_rendered;
  if (std::chrono::steady_clock::now() - ctx.last_save > std::chrono::seconds(2)) {
    save_cache(ctx.cache_file, ctx.results, ctx.cached, ctx.inputs);
    ctx.last_save = std::chrono::steady_clock::now();
  }
  if (!ctx.options.quiet) ctx.progress.update(++ctx.done);
}

// Verifies one cell and records it; a failure becomes the cell's error,
// located by database and cell, and its views are dropped.
void verify_cell(VerifyContext& ctx, const CellTask& task, std::unique_ptr<SceneDrawer>& drawer) {
  VerifyCellResult result;
  result.id = task.id;
  result.key = task.key;
  try {
    measure_cell(ctx, task, drawer, result);
  } catch (const std::exception& e) {
    result.views.clear();
    result.worst_view = -1;
    result.triptych.clear();
    const std::string what = e.what();  // located: database, cell, what
    result.error = what.rfind(ctx.database.string() + ": cell ", 0) == 0
                       ? what
                       : ctx.database.string() + ": cell " + std::to_string(task.id) + ": " + what;
  }
  record_cell(ctx, task, std::move(result));
}

// The verify's totals over every reported cell (views, blank truths, views
// equal to the truth, median PSNR), and a warning or note on stderr when
// blank truths or identical views make PSNR say nothing.
void summarise_views(const std::vector<VerifyCellResult>& cells, VerifySummary& summary) {
  const MetricStats psnr = metric_stats(cells, verify_metrics()[0]);
  summary.psnr_median_db = psnr.median;
  summary.psnr_median_reference_db = psnr.median_reference;
  for (const auto& c : cells) {
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
}

}  // namespace

VerifySummary run_verify(const std::filesystem::path& database, const std::filesystem::path& report_dir,
                         const VerifyOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  check_verify_options(options);
  const int threads = drawing_worker_threads(options.threads);

  CellDb db(database, CellDb::Mode::read_only);
  const std::filesystem::path store_path = verify_store_path(db, database, options);
  require_sound_store(store_path, options.check_store);
  GeometryStore store(store_path);
  // Cells baked from another store name chunks of another model: nothing of them can be verified.
  if (const std::string mismatch = store_mismatch(database, db.meta("store_hash"), store_path, store.summary().content_hash);
      !mismatch.empty())
    throw std::runtime_error("verify: " + mismatch);
  const BakedFacts facts = read_baked_facts(db, options);
  const nlohmann::json params = verify_params(options, facts, db);
  const SelectedCells selected = select_done_cells(db, options.cells);

  const InputFiles inputs{database, store.path()};  // no report file may be one of them
  std::filesystem::create_directories(report_dir / "views");
  const std::filesystem::path cache_file = report_dir / "verify-cells.json";
  const std::map<std::int64_t, VerifyCellResult> cached = load_cache(cache_file);
  std::map<std::int64_t, VerifyCellResult> results;
  VerifySummary summary;
  summary.cells_selected = selected.specs.size();
  // The progress bar is made after the pending cells are counted; the context holds it by reference.
  const std::vector<CellTask> pending = pending_cells(selected, params.dump(), cached, report_dir, results, summary);

  ProgressBar progress("verify", pending.size(), "cells");
  VerifyContext ctx{database, report_dir, options, db,      store,   facts,
                    inputs,   cache_file, cached,  results, summary, progress};
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::enumerable_thread_specific<std::unique_ptr<SceneDrawer>> drawers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pending.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t i = range.begin(); i != range.end(); ++i)
                          verify_cell(ctx, pending[i], drawers.local());
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
  if (options.walk_seconds > 0) input.walk = verify_walk(database, report_dir, selected.specs, options);
  const VerifyReportFiles files = write_verify_report(report_dir, input);
  summary.report_html = files.html;
  summary.report_json = files.json;
  summarise_views(input.cells, summary);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

}  // namespace cellbake
