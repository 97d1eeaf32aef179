#include "runner/walk/walk_runner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <list>
#include <map>
#include <memory>
#include <optional>

#include "pipeline/cell_grid.h"
#include "runner/progress.h"
#include "runner/walk/truth_ahead.h"
#include "runner/walk/video_writer.h"
#include "runner/walk/walk_path.h"
#include "runner/walk/walk_plot.h"
#include "stages/render/gl_context.h"
#include "stages/sample/sample_points.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "storage/output_file.h"
#include "storage/store_check.h"
#include "viewer/baked_config_text.h"
#include "viewer/camera_path.h"
#include "viewer/cell_index.h"
#include "viewer/decoded_cell.h"
#include "viewer/png_file.h"
#include "viewer/scene_drawer.h"
#include "viewer/triptych.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

constexpr std::size_t kDecodedCellsKept = 4;  // like a viewer's cache: the cells just walked through
constexpr int kPanelGap = 2;                  // pixels between the three panels
constexpr Rgba8 kGapColor{48, 48, 48, 255};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Decoded cells, the most recently used kept; failures remembered (and said once).
class CellLoader {
 public:
  CellLoader(const CellDb& db, const GeometryStore& store) : db_(db), store_(store) {}
  // The decoded cell, or nullptr (a warning the first time) when it cannot be read or decoded.
  const DecodedCell* get(std::int64_t id, bool& loaded, std::FILE* warn) {
    loaded = false;
    for (auto it = recent_.begin(); it != recent_.end(); ++it)
      if ((*it)->id == id) {
        recent_.splice(recent_.begin(), recent_, it);
        return recent_.front().get();
      }
    if (failed_.contains(id)) return nullptr;
    loaded = true;
    try {
      const auto row = db_.get_cell(id, true);
      if (!row) throw std::runtime_error("cell " + std::to_string(id) + " is not in the database");
      if (row->status != "done") throw std::runtime_error("cell " + std::to_string(id) + " is not done (" + row->status + ")");
      recent_.push_front(std::make_shared<const DecodedCell>(decode_cell(*row, &store_)));
      if (recent_.size() > kDecodedCellsKept) recent_.pop_back();
      return recent_.front().get();
    } catch (const std::exception& e) {
      failed_.emplace(id, e.what());
      if (warn) std::fprintf(warn, "warning: %s: %s; drawing ground truth there\n", db_.path().c_str(), e.what());
      return nullptr;
    }
  }
  void forget(std::int64_t id, const std::string& reason) {
    recent_.remove_if([id](const auto& c) { return c->id == id; });
    failed_.emplace(id, reason);
  }

 private:
  const CellDb& db_;
  const GeometryStore& store_;
  std::list<std::shared_ptr<const DecodedCell>> recent_;
  std::map<std::int64_t, std::string> failed_;
};

// The automatic walk's cells: done and selected, each with its navigable part.
std::vector<WalkCell> walk_cells(const CellIndex& index, const std::vector<Box3d>& regions, const std::string& selection,
                                 const std::filesystem::path& database) {
  std::vector<CellSpec> specs;
  for (const CellEntry& e : index.cells())
    if (e.done) specs.push_back({e.id, 0, e.gx, e.gy, e.gz, e.bounds});
  if (specs.empty()) throw std::runtime_error("walk: " + database.string() + " has no done cell to walk through");
  specs = select_cells(specs, selection);
  std::vector<WalkCell> cells;
  for (const CellSpec& s : specs) {
    WalkCell c{s.id, s.gx, s.gy, s.gz, s.bounds, s.bounds};
    for (const Box3d& r : regions)
      if (const Box3d part = navigable_part(s.bounds, r); !part.empty()) {
        c.navigable = part;
        break;
      }
    cells.push_back(c);
  }
  if (cells.empty()) throw std::runtime_error("walk: --cells " + selection + " selects no done cell");
  return cells;
}

}  // namespace

WalkResult run_walk(const std::filesystem::path& database, const std::filesystem::path& out_dir,
                    const WalkOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!(options.fps > 0) || !(options.speed > 0) || !(options.seconds >= 0))
    throw std::invalid_argument("walk: --fps and --speed must be positive and --seconds not negative");
  if (options.width < 8 || options.height < 8) throw std::invalid_argument("walk: image size must be at least 8x8");

  CellDb db(database, CellDb::Mode::read_only);
  const auto store_meta = db.meta("store");
  if (options.store.empty() && !store_meta)
    throw std::runtime_error("walk: " + database.string() + " has no meta 'store' (not a cell database?)");
  const std::filesystem::path store_path = options.store.empty() ? std::filesystem::path(*store_meta) : options.store;
  GeometryStore store(store_path);
  if (const std::string mismatch = store_mismatch(database, db.meta("store_hash"), store_path, store.summary().content_hash);
      !mismatch.empty())
    std::fprintf(stderr, "warning: %s\n", mismatch.c_str());
  const Vec3d up = up_axis(db.meta("up").value_or("z"));
  const std::string config_text = db.meta("config").value_or("");
  const ShadingLights lights = shading_lights(shading_of_config_text(config_text), up);
  SceneDrawOptions draw_options;
  draw_options.samples.far_budget = far_budget_of_config_text(config_text).value_or(SampleSelectionParams{}.far_budget);
  draw_options.truth_occlusion_culling = options.skip_hidden_truth;
  const CellIndex index(db);

  std::vector<PathView> views;
  if (!options.path_file.empty()) {
    views = read_camera_path(options.path_file);
    if (options.seconds > 0)
      views.resize(std::min(views.size(), std::size_t(std::floor(options.seconds * options.fps + 1e-9)) + 1));
  } else {
    AutoWalkParams params;
    params.speed = options.speed;
    params.fps = options.fps;
    params.seconds = options.seconds;
    views = auto_walk_path(walk_cells(index, regions_of_config_text(config_text), options.cells, database), up, params);
  }

  // Outputs: checked before any drawing, never over an input.
  InputFiles inputs{database, store.path()};
  if (!options.path_file.empty()) inputs.push_back(options.path_file);
  WalkResult result;
  if (!options.write_path.empty()) {
    write_output_file(options.write_path, camera_path_text(views), inputs);
    result.summary.frames = views.size();
    return result;
  }
  result.dir = out_dir;
  std::filesystem::create_directories(out_dir);
  result.plot = out_dir / "walk.svg";
  result.json = out_dir / "walk.json";
  result.text = out_dir / "walk.txt";
  result.csv = out_dir / "walk.csv";
  result.worst_png = out_dir / "worst.png";
  for (const auto& f : {result.plot, result.json, result.text, result.csv, result.worst_png}) check_output_target(f, inputs);
  const int frame_w = triptych_width(options.width, kPanelGap), frame_h = options.height;
  std::unique_ptr<VideoWriter> video;
  std::string note;
  const auto ffmpeg = options.video ? find_ffmpeg() : std::nullopt;
  if (ffmpeg) {
    result.video = out_dir / "walk.mp4";
    check_output_target(result.video, inputs);
    video = std::make_unique<VideoWriter>(*ffmpeg, result.video, frame_w, frame_h, options.fps, out_dir / "ffmpeg.log");
  } else {
    result.frames_dir = out_dir / "frames";
    std::filesystem::create_directories(result.frames_dir);
    note = options.video ? "no ffmpeg program on PATH (Debian package ffmpeg): frames written as PNG files instead of an MP4"
                         : "frames written as PNG files (no video asked for)";
    if (!options.quiet || options.video) std::fprintf(stderr, "note: %s\n", note.c_str());
  }

  SceneDrawer drawer(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)), store);
  drawer.set_shading(lights);
  std::optional<TruthAhead> ahead;
  if (options.truth_ahead) ahead.emplace(store, lights, draw_options);
  CellLoader loader(db, store);
  const auto camera_of = [&](std::size_t i) {
    return look_at_camera(views[i].eye, views[i].look, up, options.fov_y_deg, options.width, options.height,
                          options.near_plane);
  };

  ProgressBar progress("walk", views.size(), "frames");
  std::vector<WalkFrame> frames;
  frames.reserve(views.size());
  std::vector<Rgba8> worst_image;
  double worst_psnr = std::numeric_limits<double>::infinity();
  if (ahead) ahead->request(camera_of(0), options.width, options.height);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const RenderCamera camera = camera_of(i);
    TruthFrame truth;
    if (ahead) {
      truth = ahead->take();
      if (i + 1 < views.size()) ahead->request(camera_of(i + 1), options.width, options.height);
    } else {
      truth.stats = drawer.draw_truth(camera, options.width, options.height, draw_options, truth.frame);
    }
    WalkFrame f;
    f.index = int(i);
    f.t = double(i) / options.fps;
    f.eye = views[i].eye;
    f.look = views[i].look;
    f.truth_ms = truth.stats.milliseconds;
    f.truth_triangles = truth.stats.chunk_triangles;
    const CellEntry* entry = index.nearest(f.eye);
    f.cell = entry ? entry->id : 0;
    f.cell_switch = i > 0 && frames.back().cell != f.cell;
    ViewFrame impostor;
    const auto load_start = std::chrono::steady_clock::now();
    bool loaded = false;
    const DecodedCell* cell = entry ? loader.get(entry->id, loaded, stderr) : nullptr;
    f.load_ms = loaded ? ms_since(load_start) : 0;
    if (cell) {
      try {
        const SceneFrameStats st = drawer.draw_impostor(camera, options.width, options.height, *cell, draw_options, impostor);
        f.draw_ms = st.milliseconds;
        f.triangles = st.chunk_triangles + st.far_triangles;
      } catch (const std::exception& e) {
        std::fprintf(stderr, "warning: %s: cell %lld: %s; drawing ground truth there\n", database.c_str(),
                     (long long)cell->id, e.what());
        loader.forget(cell->id, e.what());
        cell = nullptr;
      }
    }
    if (!cell) {
      f.fallback = true;
      impostor = truth.frame;
      f.triangles = truth.stats.chunk_triangles;
    }
    f.frame_ms = f.load_ms + f.draw_ms;
    const ImageMetrics m = compare_frames(impostor, truth.frame);
    f.psnr_db = m.psnr_db;
    f.ssim = m.ssim;
    f.hole_fraction = m.hole_fraction;
    const std::vector<Rgba8> image =
        triptych(truth.frame, impostor, error_image(impostor, truth.frame), kPanelGap, kGapColor);
    if (!f.fallback && (worst_image.empty() || f.psnr_db < worst_psnr)) worst_psnr = f.psnr_db, worst_image = image;
    if (video) video->write(rgb24(image));
    else write_png(numbered_path(result.frames_dir / "frame.png", int(i)), frame_w, frame_h, image, inputs);
    frames.push_back(f);
    if (!options.quiet) progress.update(i + 1);
  }
  if (!options.quiet) progress.finish();
  drawer.release_context();
  ahead.reset();
  WalkSummary& s = result.summary;
  if (video) {
    video->finish();
    std::error_code ec;
    std::filesystem::remove(out_dir / "ffmpeg.log", ec);  // its messages matter only when it failed
  }
  s = summarise_walk(frames, options.fps);
  s.video = result.video.empty() ? "" : result.video.filename().string();
  s.frames_dir = result.frames_dir.empty() ? "" : result.frames_dir.filename().string();
  s.plot = result.plot.filename().string();
  s.encoder = video ? "ffmpeg " + video->codec() : "png";
  s.note = note;
  if (!worst_image.empty()) write_png(result.worst_png, frame_w, frame_h, worst_image, inputs);
  else result.worst_png.clear();
  char title[160];
  std::snprintf(title, sizeof title, "Walk: %zu frames through %zu cells (%zu switches)", s.frames, s.distinct_cells,
                s.cell_switches);
  write_output_file(result.plot, walk_plot_svg(frames, title), inputs);
  write_output_file(result.csv, walk_frames_csv(frames), inputs);
  s.wall_seconds = ms_since(t0) / 1000.0;
  nlohmann::json j = walk_summary_json(s);
  j["database"] = std::filesystem::absolute(database).string();
  j["path"] = options.path_file.empty() ? "auto" : options.path_file.string();
  j["size"] = {options.width, options.height};
  j["truth_ahead"] = options.truth_ahead;
  j["skip_hidden_truth"] = options.skip_hidden_truth;
  write_output_file(result.json, j.dump(2) + "\n", inputs);
  write_output_file(result.text, walk_summary_text(s), inputs);
  result.frames = std::move(frames);
  return result;
}

}  // namespace cellbake
