// `cellbake-view DB`: the interactive viewer (GLFW window + OpenGL 3.3 core +
// Dear ImGui panel). Per frame it finds the eye's view cell and draws its near
// field plus far-field textured depth meshes with the same SceneDrawer as
// `cellbake render`; a background thread prefetches neighbouring cells. Cells
// not (yet) in the database, failed or corrupt are drawn as ground truth and
// flagged. `--frames N --screenshot FILE` renders N frames, saves the window
// and exits (used under Xvfb by the tests). `--path FILE` walks a camera path
// (one view per frame, then exits) and `--frame-log CSV` logs and summarises
// its frame times (viewer/frame_log.h). Cell switches are staged
// (viewer/cell_switch.h): the previous cell is drawn while the new one's GPU
// uploads are spread over frames within `--upload-mb` / `--upload-ms`, and the
// neighbours load in walking order (viewer/prefetch_order.h); `--switch
// immediate` draws the new cell at once (the behaviour before, for
// comparison). Guide: docs/viewer.md.
#include <CLI/CLI.hpp>
#define GLFW_INCLUDE_NONE  // GL types come from GL/glcorearb.h (stages/render/gl_functions.h)
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "stages/render/gl_functions.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "storage/output_file.h"
#include "viewer/baked_config_text.h"
#include "viewer/camera_path.h"
#include "viewer/cell_cache.h"
#include "viewer/cell_switch.h"
#include "viewer/fly_camera.h"
#include "viewer/frame_log.h"
#include "viewer/frame_time_budget.h"
#include "viewer/image_metrics.h"
#include "viewer/interactive/glfw_window_context.h"
#include "viewer/png_file.h"
#include "viewer/prefetch_order.h"
#include "viewer/scene_drawer.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

struct Options {
  std::string database, store, size = "1280x720", eye, look, screenshot, path, frame_log, switch_mode = "staged";
  int frames = 0;
  double fov = 60, near = 0.05, cache_mb = 1024, upload_mb = 8, upload_ms = 6;
  double frame_ms = 66;  // frame time aimed at while moving: chunks drawn at coarser levels to fit (0: as baked)
};

// The triangles a frame drew: chunks (near field, far geometry) and depth meshes.
std::uint64_t drawn_triangles(const SceneFrameStats& s) { return s.chunk_triangles + s.far_triangles; }

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

// How many decoded cells besides the eye's fit the cache, judged by the
// cells held now (at least one).
std::size_t prefetch_limit(const CellCacheStats& s) {
  if (s.cells == 0 || s.bytes == 0) return 1;
  const double per_cell = static_cast<double>(s.bytes) / static_cast<double>(s.cells);
  return static_cast<std::size_t>(std::max(1.0, std::floor(static_cast<double>(s.max_bytes) / per_cell) - 1));
}

enum class DrawMode : int { both, near_only, far_only, truth };

struct ViewerState {
  DrawMode mode = DrawMode::both;
  bool wireframe = false, tint_by_cell = false, show_holes = false, freeze = false;
  std::int64_t frozen_cell = 0;
  int jump_cell = 1;
  float fov = 60;
  bool mouse_look = false;
  double last_x = 0, last_y = 0;
};

struct FrameInfo {
  std::int64_t cell_id = 0;
  std::string flag;  // why ground truth is shown instead of the impostor ("" = impostor)
  double cull_half_size = 0;
  SceneFrameStats stats;
  std::uint64_t near_triangles = 0;
  double frame_ms = 0;
  std::optional<ImageMetrics> holes;
};

void read_window(const GlFunctions& gl, int w, int h, std::vector<Rgba8>& out) {
  std::vector<Rgba8> raw(static_cast<std::size_t>(w) * h);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  gl.ReadBuffer(GL_BACK);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.ReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, raw.data());
  out.resize(raw.size());
  for (int row = 0; row < h; ++row)
    std::copy_n(raw.data() + static_cast<std::size_t>(h - 1 - row) * w, w, out.data() + static_cast<std::size_t>(row) * w);
  for (Rgba8& p : out) p.a = 255;
}

// Horizontal map axes (a, b with a x b = up) for the mini-map.
void map_axes(const Vec3d& up, int& a, int& b) {
  if (std::abs(up.y) > 0.5) a = 2, b = 0;
  else a = 0, b = 1;
}

void draw_minimap(const CellIndex& index, const FlyCamera& fly, std::int64_t current, ViewerState& state) {
  const Box3d all = index.bounds();
  if (all.empty()) {
    ImGui::TextUnformatted("(no cells yet)");
    return;
  }
  int a = 0, b = 1;
  map_axes(fly.up, a, b);
  const ImVec2 size(260, 200);
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("minimap", size);
  const bool clicked = ImGui::IsItemClicked();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddRectFilled(origin, ImVec2(origin.x + size.x, origin.y + size.y), IM_COL32(25, 25, 30, 255));
  const double span = std::max(all.hi[a] - all.lo[a], all.hi[b] - all.lo[b]) * 1.05;
  const double scale = std::min(size.x, size.y) / span;
  const auto to_screen = [&](double u, double v) {
    return ImVec2(origin.x + 4 + static_cast<float>((u - all.lo[a]) * scale),
                  origin.y + size.y - 4 - static_cast<float>((v - all.lo[b]) * scale));
  };
  const ImVec2 mouse = ImGui::GetMousePos();
  for (const CellEntry& c : index.cells()) {
    const ImVec2 p0 = to_screen(c.bounds.lo[a], c.bounds.hi[b]), p1 = to_screen(c.bounds.hi[a], c.bounds.lo[b]);
    const ImU32 fill = c.done ? IM_COL32(40, 120, 60, 255) : IM_COL32(150, 40, 40, 255);
    draw->AddRectFilled(p0, p1, fill);
    draw->AddRect(p0, p1, c.id == current ? IM_COL32(255, 230, 0, 255) : IM_COL32(0, 0, 0, 255));
    if (clicked && mouse.x >= p0.x && mouse.x <= p1.x && mouse.y >= p0.y && mouse.y <= p1.y) state.jump_cell = static_cast<int>(c.id);
  }
  draw->AddCircleFilled(to_screen(fly.position[a], fly.position[b]), 3.5f, IM_COL32(255, 255, 255, 255));
  const Vec3d f = fly.forward();
  const ImVec2 p = to_screen(fly.position[a], fly.position[b]);
  draw->AddLine(p, ImVec2(p.x + 12 * static_cast<float>(f[a]), p.y - 12 * static_cast<float>(f[b])), IM_COL32(255, 255, 255, 255));
}

// Turns the camera to look along `d` (yaw about up, pitch above the horizontal).
void look_along(FlyCamera& fly, const Vec3d& d, const Vec3d& up) {
  int a = 0, b = 1;
  map_axes(up, a, b);
  fly.yaw_deg = std::atan2(d[b], d[a]) * 180 / 3.14159265358979323846;
  fly.pitch_deg = std::atan2(dot(d, up), std::hypot(d[a], d[b])) * 180 / 3.14159265358979323846;
}

// glfwTerminate when the run ends, however it ends.
struct GlfwGuard {
  ~GlfwGuard() { glfwTerminate(); }
};

// The OpenGL 3.3 core window (vsync only when interactive). Throws when there is none.
GLFWwindow* open_window(int width, int height, const std::string& database, int total_frames) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  GLFWwindow* window = glfwCreateWindow(width, height, ("cellbake view " + database).c_str(), nullptr, nullptr);
  if (!window) throw std::runtime_error("cannot create an OpenGL 3.3 core window");
  glfwMakeContextCurrent(window);
  glfwSwapInterval(total_frames > 0 ? 0 : 1);
  return window;
}

// What a viewer run reads, set up before its window opens: the database's
// meta (store, up axis, config), the store, the cell cache and the camera path.
struct ViewerInputs {
  const Options& opt;
  const CellDb& meta_db;
  const std::string& store_path;
  const Vec3d up;
  GeometryStore& store;
  CellCache& cache;
  const std::vector<PathView>& path;
  int width = 0, height = 0;
  bool scripted = false;     // --path: one view of the path per frame
  bool staged = false;       // --switch staged
  int total_frames = 0;      // frames to draw before exiting (0: until the window closes)
  UploadBudget budget;       // staged switches' GPU uploads per frame
};

// A viewer session in its open window: the drawer, the display texture, the
// camera, the panel's state, and per frame what was drawn (and with --path, the
// frame log). run() is the frame loop.
class ViewerSession {
 public:
  ViewerSession(const ViewerInputs& in, GLFWwindow* window);
  // Draws frames until the window closes or the frames (--frames, --path) are
  // drawn; then with --path prints the frame summary and writes the frame log,
  // and deletes the display texture.
  void run();

 private:
  void place_camera(const CellIndex& index);
  void load_first_cell(const CellIndex& index);
  void steer(int frame_number, double dt, const ImGuiIO& io);
  std::shared_ptr<const DecodedCell> choose_cell(const CellIndex& index, UploadProgress& spent);
  std::shared_ptr<const DecodedCell> choose_staged_cell(const CellIndex& index, const CellEntry& entry, double reach,
                                                        UploadProgress& spent);
  const std::vector<Rgba8>& draw_scene(const std::shared_ptr<const DecodedCell>& cell, int fw, int fh);
  void show_image(const std::vector<Rgba8>& image, int fw, int fh);
  void panel_stats(const std::shared_ptr<const DecodedCell>& cell);
  void panel_controls(const CellIndex& index);
  void save_screenshot(int fw, int fh);
  void log_frame(int frame_number, std::chrono::steady_clock::time_point frame_start,
                 const std::shared_ptr<const DecodedCell>& cell, const UploadProgress& spent,
                 std::uint64_t uploaded_before);

  const ViewerInputs& in_;
  const Options& opt_;
  GLFWwindow* window_;
  std::shared_ptr<GlfwWindowContext> context_;
  SceneDrawer drawer_;
  std::uint64_t far_budget_ = 0;  // view.far_budget as the bake asked (older databases: the default)
  GlFunctions gl_;
  GLuint display_ = 0;            // the texture the frame is shown through
  FlyCamera fly_;
  Vec3d start_;
  ViewerState state_;
  FrameInfo info_;
  ViewFrame frame_, truth_;
  std::vector<Rgba8> shown_;
  CellSwitch cell_switch_;
  EyeMotion motion_;
  std::vector<FrameRecord> log_;
  std::int64_t previous_cell_ = 0;
  std::optional<FrameTimeBudget> frame_budget_;  // --frame-ms > 0
  std::uint64_t chunk_budget_ = 0;               // this frame's chunk triangles allowed (0: no limit)
  SceneFrameStats last_stats_;                   // the last frame drawn (info_ starts afresh each frame)
  static constexpr int kStillFramesToRefine = 3;  // frames of one view before it is drawn as baked
  FlyCamera last_view_;
  int still_frames_ = 0;
};

ViewerSession::ViewerSession(const ViewerInputs& in, GLFWwindow* window)
    : in_(in),
      opt_(in.opt),
      window_(window),
      context_(std::make_shared<GlfwWindowContext>(window)),
      drawer_(context_, in.store, SceneDrawerParams{}) {
  drawer_.set_shading(shading_lights(shading_of_config_text(in.meta_db.meta("config").value_or("")), in.up));
  far_budget_ = far_budget_of_config_text(in.meta_db.meta("config").value_or(""))
                    .value_or(SampleSelectionParams{}.far_budget);
  gl_ = load_gl_functions(*context_);
  gl_.GenTextures(1, &display_);
  gl_.BindTexture(GL_TEXTURE_2D, display_);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  const auto index0 = in_.cache.index();
  place_camera(*index0);
  state_.fov = static_cast<float>(opt_.fov);
  if (opt_.frame_ms > 0) frame_budget_.emplace(opt_.frame_ms);
  if (in_.scripted) load_first_cell(*index0);
}

// The camera's start: the path's first view, else --eye (looking at --look),
// else the first cell's centre, else the model's; walking on the model's floor.
void ViewerSession::place_camera(const CellIndex& index) {
  const Vec3d& up = in_.up;
  fly_.up = up;
  const Box3d model = in_.store.model_bounds();
  fly_.floor = model.empty() ? 0 : dot(model.lo, up);
  start_ = in_.scripted              ? in_.path.front().eye
           : !opt_.eye.empty()       ? parse_point(opt_.eye, "--eye")
           : !index.cells().empty() ? index.cells().front().bounds.center()
                                     : model.center();
  fly_.position = start_;
  if (!opt_.look.empty() || in_.scripted)
    look_along(fly_, (in_.scripted ? in_.path.front().look : parse_point(opt_.look, "--look")) - start_, up);
  fly_.eye_height = dot(start_, up) - fly_.floor;
  fly_.speed = std::max(0.5, 0.02 * length(model.extent()));
}

// Loading (--path): the first cell decoded and uploaded whole before the first frame.
void ViewerSession::load_first_cell(const CellIndex& index) {
  const auto t = std::chrono::steady_clock::now();
  if (const CellEntry* first = index.containing(start_))
    if (const auto cell = in_.cache.get_blocking(first->id)) {
      drawer_.prepare(*cell);
      while (!drawer_.upload_some(*cell, {std::numeric_limits<std::size_t>::max(), 1e300}).complete) {
      }
      // Four frames drawn unseen: the first measures the frame time budget,
      // the others settle it and upload the levels they draw, so the first
      // frame shown is budgeted and finds them ready.
      for (int warm = 0; frame_budget_ && warm < 4; ++warm) {
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(window_, &fw, &fh);
        const auto d = std::chrono::steady_clock::now();
        still_frames_ = 0;  // the same view each time, but budgeted like a walk's
        draw_scene(cell, std::max(fw, 1), std::max(fh, 1));
        frame_budget_->add(elapsed_ms(d), drawn_triangles(info_.stats));
      }
    }
  std::printf("loading: first cell decoded and uploaded%s in %.1f ms\n",
              frame_budget_ ? ", four frames drawn unseen for the frame time budget," : "", elapsed_ms(t));
}

// Moves the camera: to the path's view of this frame (--path), else by the
// keys (unless the panel has them) and, held, the mouse.
void ViewerSession::steer(int frame_number, double dt, const ImGuiIO& io) {
  if (in_.scripted) {
    // The path's view of this frame; the keys and the mouse move nothing.
    const PathView& view = in_.path[static_cast<std::size_t>(frame_number)];
    fly_.position = view.eye;
    look_along(fly_, view.look - view.eye, in_.up);
  } else if (!io.WantCaptureKeyboard) {
    const auto key = [&](int k) { return glfwGetKey(window_, k) == GLFW_PRESS ? 1.0 : 0.0; };
    // Esc or Ctrl+Q quits (Q alone moves down).
    if (key(GLFW_KEY_ESCAPE) || ((key(GLFW_KEY_LEFT_CONTROL) || key(GLFW_KEY_RIGHT_CONTROL)) && key(GLFW_KEY_Q)))
      glfwSetWindowShouldClose(window_, GLFW_TRUE);
    const double boost = key(GLFW_KEY_LEFT_SHIFT) ? 4.0 : 1.0;
    fly_.move((key(GLFW_KEY_W) - key(GLFW_KEY_S)) * boost, (key(GLFW_KEY_D) - key(GLFW_KEY_A)) * boost,
              (key(GLFW_KEY_E) - key(GLFW_KEY_Q)) * boost, dt);
  }
  double mx = 0, my = 0;
  glfwGetCursorPos(window_, &mx, &my);
  const bool look_button = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
                           (glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS && !io.WantCaptureMouse);
  if (look_button && state_.mouse_look && !in_.scripted)
    fly_.turn(-(mx - state_.last_x) * 0.2, -(my - state_.last_y) * 0.2);
  state_.mouse_look = look_button;
  state_.last_x = mx, state_.last_y = my;
}

// The eye's cell (or the frozen one) into info_, its decoded far field to draw
// (null: draw the truth, info_.flag says why), and the neighbours prefetched.
std::shared_ptr<const DecodedCell> ViewerSession::choose_cell(const CellIndex& index, UploadProgress& spent) {
  const CellEntry* entry = state_.freeze ? index.find(state_.frozen_cell) : index.containing(fly_.position);
  if (!state_.freeze && entry) state_.frozen_cell = entry->id;
  std::shared_ptr<const DecodedCell> cell;
  info_ = {};
  if (!entry) {
    info_.flag = "eye outside every baked cell";
    return cell;
  }
  info_.cell_id = entry->id;
  info_.cull_half_size = entry->cull_half_size;
  const double reach = 1.01 * (entry->bounds.hi.x - entry->bounds.lo.x);
  if (in_.staged) {
    cell = choose_staged_cell(index, *entry, reach, spent);
  } else {
    cell = in_.total_frames > 0 ? in_.cache.get_blocking(entry->id) : in_.cache.get(entry->id);
    std::vector<std::int64_t> neighbours;
    for (const CellEntry& c : index.cells())
      if (c.id != entry->id && distance_to_box(entry->bounds.center(), c.bounds) <= reach) neighbours.push_back(c.id);
    in_.cache.prefetch(neighbours);
  }
  if (!cell && info_.flag.empty()) {
    const std::string failure = in_.cache.failure(entry->id);
    info_.flag = failure.empty() ? "loading" : failure;
  }
  return cell;
}

// --switch staged: the neighbours prefetched in walking order (as many as the
// cache holds), and the cell to draw from the switch: the previous one while
// the eye's cell uploads within the budget.
std::shared_ptr<const DecodedCell> ViewerSession::choose_staged_cell(const CellIndex& index, const CellEntry& entry,
                                                                     double reach, UploadProgress& spent) {
  motion_.add(fly_.position);
  PrefetchOrder order = prefetch_order(index, entry, fly_.position, motion_.velocity(), reach);
  order.ids.resize(std::min(order.ids.size(), prefetch_limit(in_.cache.stats())));
  in_.cache.prefetch(order.ids);
  // Blocks only while nothing has been drawn yet (--frames, --path).
  const bool wait = in_.total_frames > 0 && !cell_switch_.shown();
  const auto target = wait ? in_.cache.get_blocking(entry.id) : in_.cache.get(entry.id);
  const auto heading = order.heading ? in_.cache.peek(order.heading) : nullptr;
  std::shared_ptr<const DecodedCell> cell;
  if (target || in_.cache.failure(entry.id).empty()) {
    try {
      cell = cell_switch_.choose(target, heading, drawer_, in_.budget, spent);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "warning: cell %lld: %s; drawing ground truth\n", (long long)entry.id, e.what());
      cell_switch_.reset();
      info_.flag = std::string("uploading failed: ") + e.what();
    }
  }
  return cell;
}

// Draws the frame at fw x fh as the panel asks (impostor, near or far field
// only, or the truth; the truth when there is no cell or drawing it fails),
// timed. Returns the image to show: the frame, or with "show holes" its error image.
const std::vector<Rgba8>& ViewerSession::draw_scene(const std::shared_ptr<const DecodedCell>& cell, int fw, int fh) {
  const RenderCamera camera = fly_.camera(state_.fov, fw, fh, opt_.near);
  SceneDrawOptions options;
  options.wireframe = state_.wireframe;
  options.tint_by_cell = state_.tint_by_cell;
  options.near_field = state_.mode != DrawMode::far_only;
  options.far_field = state_.mode != DrawMode::near_only;
  options.samples.far_budget = far_budget_;
  // A view held still for a few frames is drawn as baked (refined); a moving
  // one within the frame-time budget.
  const bool same_view = fly_.position == last_view_.position && fly_.yaw_deg == last_view_.yaw_deg &&
                         fly_.pitch_deg == last_view_.pitch_deg;
  still_frames_ = same_view ? still_frames_ + 1 : 0;
  last_view_ = fly_;
  if (frame_budget_ && still_frames_ < kStillFramesToRefine) {
    // The last frame's depth-mesh triangles are taken as this frame's too.
    options.max_chunk_triangles = chunk_allowance(frame_budget_->triangles(), last_stats_.far_triangles);
  }
  chunk_budget_ = options.max_chunk_triangles;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (state_.mode == DrawMode::truth || !cell) {
      info_.stats = drawer_.draw_truth(camera, fw, fh, options, frame_);
    } else {
      info_.stats = drawer_.draw_impostor(camera, fw, fh, *cell, options, frame_);
      info_.near_triangles = options.near_field ? cell->near_triangles : 0;
    }
  } catch (const std::exception& e) {
    info_.flag = std::string("drawing failed: ") + e.what();
    std::fprintf(stderr, "warning: cell %lld: %s; drawing ground truth\n", (long long)info_.cell_id, e.what());
    info_.stats = drawer_.draw_truth(camera, fw, fh, options, frame_);
  }
  const std::vector<Rgba8>* image = &frame_.color;
  if (state_.show_holes && cell && state_.mode != DrawMode::truth) {
    drawer_.draw_truth(camera, fw, fh, SceneDrawOptions{}, truth_);
    info_.holes = compare_frames(frame_, truth_);
    shown_ = error_image(frame_, truth_);
    image = &shown_;
  }
  info_.frame_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  last_stats_ = info_.stats;
  return *image;
}

// The image into the display texture, and the window's framebuffer cleared for it.
void ViewerSession::show_image(const std::vector<Rgba8>& image, int fw, int fh) {
  context_->make_current();
  gl_.BindTexture(GL_TEXTURE_2D, display_);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, fw, fh, 0, GL_RGBA, GL_UNSIGNED_BYTE, image.data());
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl_.Viewport(0, 0, fw, fh);
  const float black[4] = {0, 0, 0, 1};
  gl_.ClearBufferfv(GL_COLOR, 0, black);
}

// The panel's figures: the cell, why the truth is shown, triangles, far field,
// times, the cell drawn meanwhile, the cache, GPU memory and holes.
void ViewerSession::panel_stats(const std::shared_ptr<const DecodedCell>& cell) {
  ImGui::Text("cell %lld   cull box half-size %.2f", (long long)info_.cell_id, info_.cull_half_size);
  if (!info_.flag.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "ground truth: %s", info_.flag.c_str());
  ImGui::Text("near %llu tris   far %llu tris   chunks %llu (%llu tris)", (unsigned long long)info_.near_triangles,
              (unsigned long long)info_.stats.far_triangles, (unsigned long long)info_.stats.chunks_drawn,
              (unsigned long long)info_.stats.chunk_triangles);
  ImGui::Text("far field: %llu samples drawn (budget %llu triangles)", (unsigned long long)info_.stats.samples_drawn,
              (unsigned long long)far_budget_);
  if (frame_budget_)
    ImGui::Text("frame time budget %.0f ms: %s", frame_budget_->target_ms(),
                chunk_budget_                             ? ("chunks up to " + std::to_string(chunk_budget_) + " tris").c_str()
                : still_frames_ >= kStillFramesToRefine ? "still: drawn as baked"
                                                        : "no limit yet");
  ImGui::Text("frame %.1f ms   draw %.1f ms", info_.frame_ms, info_.stats.milliseconds);
  if (cell && cell->id != info_.cell_id)
    ImGui::Text("drawing cell %lld while cell %lld uploads", (long long)cell->id, (long long)info_.cell_id);
  const CellCacheStats cs = in_.cache.stats();
  ImGui::Text("cache: %zu cells, %.1f MB, hits %llu, misses %llu, failed %llu", cs.cells, cs.bytes / 1048576.0,
              (unsigned long long)cs.hits, (unsigned long long)cs.misses, (unsigned long long)cs.failures);
  ImGui::Text("GPU: far field %.1f MB, chunks %.1f MB", drawer_.tdm_gpu_bytes() / 1048576.0,
              drawer_.chunk_stats().cached_bytes / 1048576.0);
  if (info_.holes)
    ImGui::Text("holes %.4f  skins %.4f  PSNR %.1f dB", info_.holes->hole_fraction, info_.holes->skin_fraction,
                info_.holes->psnr_db);
}

// The panel's controls: draw mode, display options, camera, the jump to a cell
// (by number or a click on the mini-map) and the keys' help.
void ViewerSession::panel_controls(const CellIndex& index) {
  int mode = static_cast<int>(state_.mode);
  ImGui::RadioButton("both", &mode, 0);
  ImGui::SameLine();
  ImGui::RadioButton("near only", &mode, 1);
  ImGui::SameLine();
  ImGui::RadioButton("far only", &mode, 2);
  ImGui::SameLine();
  ImGui::RadioButton("ground truth", &mode, 3);
  state_.mode = static_cast<DrawMode>(mode);
  ImGui::Checkbox("wireframe", &state_.wireframe);
  ImGui::SameLine();
  ImGui::Checkbox("colour by cell", &state_.tint_by_cell);
  ImGui::Checkbox("show holes", &state_.show_holes);
  ImGui::SameLine();
  ImGui::Checkbox("freeze cell", &state_.freeze);
  ImGui::Checkbox("walk", &fly_.walk);
  float speed = static_cast<float>(fly_.speed), eye_height = static_cast<float>(fly_.eye_height);
  ImGui::SliderFloat("speed", &speed, 0.1f, 200.0f, "%.1f", ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("eye height", &eye_height, 0.1f, 10.0f);
  ImGui::SliderFloat("fov", &state_.fov, 20.0f, 120.0f);
  fly_.speed = speed, fly_.eye_height = eye_height;
  ImGui::Text("eye %.2f %.2f %.2f", fly_.position.x, fly_.position.y, fly_.position.z);
  ImGui::SetNextItemWidth(120);
  ImGui::InputInt("##cell", &state_.jump_cell);
  ImGui::SameLine();
  bool jump = ImGui::Button("jump to cell");
  const int before_click = state_.jump_cell;
  draw_minimap(index, fly_, info_.cell_id, state_);  // a click on a cell sets jump_cell
  jump = jump || state_.jump_cell != before_click;
  if (jump) {
    if (const CellEntry* target = index.find(state_.jump_cell)) {
      fly_.position = target->bounds.center();
      fly_.eye_height = dot(fly_.position, in_.up) - fly_.floor;
    }
  }
  ImGui::TextUnformatted("WASD move, Q/E down/up, shift faster, right mouse look, Esc or Ctrl+Q quit");
}

// --screenshot: the window saved as a PNG after the last frame.
void ViewerSession::save_screenshot(int fw, int fh) {
  std::vector<Rgba8> pixels;
  read_window(gl_, fw, fh, pixels);
  write_png(opt_.screenshot, fw, fh, pixels, {opt_.database, opt_.store});
  std::printf("screenshot %s (%dx%d) after %d frames, cell %lld%s\n", opt_.screenshot.c_str(), fw, fh,
              in_.total_frames, (long long)info_.cell_id, info_.flag.empty() ? "" : " (ground truth)");
}

// --path: the frame's record (cell, switch, times, uploads, cache, triangles).
void ViewerSession::log_frame(int frame_number, std::chrono::steady_clock::time_point frame_start,
                              const std::shared_ptr<const DecodedCell>& cell, const UploadProgress& spent,
                              std::uint64_t uploaded_before) {
  FrameRecord r;
  r.frame = frame_number;
  r.cell_id = info_.cell_id;
  r.drawn_cell = cell ? cell->id : 0;
  r.switched = frame_number > 0 && info_.cell_id != previous_cell_;
  r.frame_ms = elapsed_ms(frame_start);
  r.draw_ms = info_.stats.milliseconds;
  r.upload_ms = spent.milliseconds + info_.stats.prepare_milliseconds;
  r.upload_bytes = drawer_.uploaded_bytes() - uploaded_before;
  r.cache_bytes = in_.cache.stats().bytes;
  r.triangles = drawn_triangles(info_.stats);
  r.far_geometry_triangles = info_.stats.far_geometry_triangles;
  r.chunk_budget = chunk_budget_;
  log_.push_back(r);
  previous_cell_ = info_.cell_id;
}

void ViewerSession::run() {
  auto last = std::chrono::steady_clock::now();
  for (int frame_number = 0; !glfwWindowShouldClose(window_); ++frame_number) {
    const auto frame_start = std::chrono::steady_clock::now();
    const std::uint64_t uploaded_before = drawer_.uploaded_bytes();
    UploadProgress spent;
    glfwPollEvents();
    const auto now = std::chrono::steady_clock::now();
    const double dt = std::min(0.1, std::chrono::duration<double>(now - last).count());
    last = now;
    ImGuiIO& io = ImGui::GetIO();
    steer(frame_number, dt, io);

    // The eye's cell, its decoded far field, and prefetching of the neighbours.
    const auto index = in_.cache.index();
    const std::shared_ptr<const DecodedCell> cell = choose_cell(*index, spent);
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    fw = std::max(fw, 1), fh = std::max(fh, 1);
    show_image(draw_scene(cell, fw, fh), fw, fh);

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(display_)),
                                             ImVec2(0, 0), io.DisplaySize);
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    // Sized to its contents every frame: no stats line is clipped.
    ImGui::Begin("cellbake", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    panel_stats(cell);
    ImGui::Separator();
    panel_controls(*index);
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    const bool last_frame = in_.total_frames > 0 && frame_number + 1 >= in_.total_frames;
    if (last_frame && !opt_.screenshot.empty()) save_screenshot(fw, fh);
    glfwSwapBuffers(window_);
    if (frame_budget_)
      frame_budget_->add(elapsed_ms(frame_start), drawn_triangles(info_.stats));
    if (in_.scripted) log_frame(frame_number, frame_start, cell, spent, uploaded_before);
    if (last_frame) break;
  }
  if (in_.scripted) {
    const CellCacheStats cs = in_.cache.stats();
    std::printf("%s", frame_summary_text(summarize_frames(log_, cs.max_bytes)).c_str());
    if (!opt_.frame_log.empty()) {
      write_output_file(opt_.frame_log, frame_log_csv(log_), {opt_.database, in_.store_path, opt_.path});
      std::printf("frame log: %s\n", opt_.frame_log.c_str());
    }
  }
  context_->make_current();
  gl_.DeleteTextures(1, &display_);
}

int run(const Options& opt) {
  CellDb meta_db(opt.database, CellDb::Mode::read_only);
  const std::string store_path = opt.store.empty() ? meta_db.meta("store").value_or("") : opt.store;
  if (store_path.empty()) throw std::runtime_error(opt.database + " has no meta 'store'; pass --store");
  const Vec3d up = up_axis(meta_db.meta("up").value_or("z"));
  GeometryStore store(store_path);
  CellCacheParams cache_params;
  cache_params.max_bytes = static_cast<std::size_t>(opt.cache_mb * 1048576.0);
  cache_params.source = &store;  // far pieces cut from their stored chunks on the loader thread
  cache_params.load_chunks = opt.switch_mode == "staged";  // and the chunks read from the store there too
  CellCache cache(opt.database, cache_params);
  const auto [width, height] = parse_image_size(opt.size);
  const std::vector<PathView> path = opt.path.empty() ? std::vector<PathView>{} : read_camera_path(opt.path);
  const bool scripted = !path.empty();
  const int total_frames = scripted ? static_cast<int>(path.size()) : opt.frames;
  const ViewerInputs inputs{opt,    meta_db, store_path, up,      store,        cache,
                            path,   width,   height,     scripted, opt.switch_mode == "staged", total_frames,
                            UploadBudget{static_cast<std::size_t>(opt.upload_mb * 1048576.0), opt.upload_ms}};

  glfwSetErrorCallback([](int code, const char* text) { std::fprintf(stderr, "glfw error %d: %s\n", code, text); });
  if (!glfwInit()) throw std::runtime_error("cannot initialise GLFW (no display? run under xvfb-run)");
  GlfwGuard glfw_guard;
  GLFWwindow* window = open_window(width, height, opt.database, total_frames);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330");
  {
    ViewerSession session(inputs, window);
    session.run();
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  cellbake::Options opt;
  CLI::App app{"cellbake-view: interactive viewer of a cell database (also `cellbake view`)"};
  app.add_option("database", opt.database, "Cell database")->required();
  app.add_option("--store", opt.store, "Geometry store (default: the one the database names)");
  app.add_option("--size", opt.size, "Window size WxH");
  app.add_option("--eye", opt.eye, "Start position X,Y,Z (default: the first cell's centre)");
  app.add_option("--look", opt.look, "Start looking at X,Y,Z");
  app.add_option("--fov", opt.fov, "Vertical field of view, degrees")->check(CLI::Range(20.0, 120.0));
  app.add_option("--near", opt.near, "Near plane, model units")->check(CLI::PositiveNumber);
  app.add_option("--cache-mb", opt.cache_mb, "Memory cap of decoded cells, MiB")->check(CLI::PositiveNumber);
  CLI::Option* frames =
      app.add_option("--frames", opt.frames, "Render this many frames, then exit")->check(CLI::NonNegativeNumber);
  app.add_option("--screenshot", opt.screenshot, "With --frames or --path: save the last frame as this PNG");
  app.add_option("--path", opt.path,
                 "Scripted walk: one view of this camera path file per frame (\"ex ey ez lx ly lz\" lines, as "
                 "`cellbake walk --write-path` writes), then exit with a summary of frame times")
      ->excludes(frames);
  app.add_option("--frame-log", opt.frame_log,
                 "With --path: write one CSV line per frame (cell, switch, frame ms, uploads, cache bytes)");
  app.add_option("--switch", opt.switch_mode,
                 "Cell switches: staged (keep drawing the previous cell while the new one uploads within the "
                 "budget; prefetch in walking order) or immediate (draw the new cell at once, as before)")
      ->check(CLI::IsMember({"staged", "immediate"}))
      ->capture_default_str();
  app.add_option("--upload-mb", opt.upload_mb, "Staged switches: GPU upload budget per frame, MiB")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--upload-ms", opt.upload_ms, "Staged switches: GPU upload budget per frame, milliseconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--frame-ms", opt.frame_ms,
                 "Frame time to aim at while the view moves: chunks drawn at coarser store levels, least projected "
                 "error first, while frames take longer (the triangles a frame may draw follow recent frames' time "
                 "per triangle); a view held still for 3 frames is drawn as baked; 0: always as baked")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    return cellbake::run(opt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cellbake view: error: %s\n", e.what());
    return 1;
  }
}
