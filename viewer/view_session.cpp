#include "viewer/view_session.h"

#include "viewer/baked_config_text.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "stages/render/gl_context.h"
#include "storage/store_check.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

constexpr std::size_t kDecodedCellsKept = 16;

std::filesystem::path store_of(const CellDb& db, const std::filesystem::path& override_path) {
  if (!override_path.empty()) return override_path;
  const auto store = db.meta("store");
  if (!store) throw std::runtime_error("view: " + db.path().string() + " has no meta 'store' (not a cell database?)");
  return *store;
}

}  // namespace

ViewMode parse_view_mode(const std::string& text) {
  if (text == "impostor") return ViewMode::impostor;
  if (text == "truth") return ViewMode::truth;
  if (text == "diff") return ViewMode::diff;
  throw std::invalid_argument("view: mode must be impostor, truth or diff, got \"" + text + "\"");
}

ViewSession::ViewSession(const std::filesystem::path& database, const std::filesystem::path& store_override)
    : db_(std::make_unique<CellDb>(database, CellDb::Mode::read_only)),
      store_(std::make_unique<GeometryStore>(store_of(*db_, store_override))),
      index_(*db_),
      up_(up_axis(db_->meta("up").value_or("z"))),
      far_budget_(far_budget_of_config_text(db_->meta("config").value_or("")).value_or(SampleSelectionParams{}.far_budget)),
      drawer_(std::make_unique<SceneDrawer>(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)),
                                            *store_)) {
  drawer_->set_shading(shading_lights(shading_of_config_text(db_->meta("config").value_or("")), up_));
}

ViewSession::ViewSession(StoreOnly, const std::filesystem::path& store)
    : store_(std::make_unique<GeometryStore>(store)),
      up_(up_axis(store_->summary().up.empty() ? "z" : store_->summary().up)),
      far_budget_(SampleSelectionParams{}.far_budget),
      drawer_(std::make_unique<SceneDrawer>(std::shared_ptr<GlContext>(create_headless_gl_context(1, 1)),
                                            *store_)) {
  drawer_->set_shading(shading_lights(ShadingParams{}, up_));
}

void default_overview(const Box3d& bounds, const Vec3d& up, ViewRequest& request) {
  const Vec3d centre = (bounds.lo + bounds.hi) * 0.5;
  const double diagonal = std::max(length(bounds.hi - bounds.lo), 1e-3);
  // Two horizontal axes: x, and whichever of y / z is not up.
  const Vec3d a{1, 0, 0};
  const Vec3d b = up.z != 0 ? Vec3d{0, -1, 0} : Vec3d{0, 0, 1};
  Vec3d dir = a * 0.8 + b + up * 0.7;
  dir = dir * (1.0 / length(dir));
  request.look = centre;
  request.eye = centre + dir * diagonal;
}

ViewSession::~ViewSession() = default;

std::string ViewSession::store_mismatch() const {
  if (!db_) return "";
  return cellbake::store_mismatch(db_->path(), db_->meta("store_hash"), store_->path(), store_->summary().content_hash);
}

const DecodedCell* ViewSession::load_cell(std::int64_t id, std::string& reason, std::FILE* warn) {
  if (auto it = decoded_.find(id); it != decoded_.end()) return it->second.get();
  if (auto it = failures_.find(id); it != failures_.end()) {
    reason = it->second;
    return nullptr;
  }
  try {
    const auto row = db_->get_cell(id, true);
    if (!row) throw std::runtime_error("cell " + std::to_string(id) + " is not in the database");
    auto cell = std::make_shared<const DecodedCell>(decode_cell(*row, store_.get()));
    if (decoded_.size() >= kDecodedCellsKept) decoded_.clear();  // a path walks on; the next cells reload
    return (decoded_[id] = std::move(cell)).get();
  } catch (const std::exception& e) {
    reason = e.what();
    failures_[id] = reason;
    if (warn) std::fprintf(warn, "warning: %s; drawing ground truth there\n", reason.c_str());
    return nullptr;
  }
}

ViewResult ViewSession::render(const ViewRequest& r, ViewMode mode, std::FILE* warn) {
  if (!db_ && mode != ViewMode::truth)
    throw std::invalid_argument("view: " + store_->path().string() +
                                " is a geometry store (not baked): only the ground truth can be drawn (--mode truth)");
  const RenderCamera camera = look_at_camera(r.eye, r.look, up_, r.fov_y_deg, r.width, r.height, r.near_plane);
  ViewResult result;
  const CellEntry* entry = r.cell ? index_.find(*r.cell) : index_.nearest(r.eye);
  if (r.cell && !entry) throw std::invalid_argument("view: cell " + std::to_string(*r.cell) + " is not in the database");
  SceneDrawOptions options;
  options.samples.far_budget = r.far_budget.value_or(far_budget_);
  options.samples.max_samples = r.max_samples;
  const bool want_impostor = mode != ViewMode::truth, want_truth = mode != ViewMode::impostor;

  if (entry) result.cell_id = entry->id;
  if (want_impostor) {
    const DecodedCell* cell = nullptr;
    if (entry) {
      cell = load_cell(entry->id, result.fallback_reason, warn);
    } else {
      result.fallback_reason = "the database has no cells";
    }
    if (cell) {
      try {
        ViewFrame frame;
        drawer_->draw_impostor(camera, r.width, r.height, *cell, options, frame);  // warm-up: uploads
        result.impostor_stats = drawer_->draw_impostor(camera, r.width, r.height, *cell, options, frame);
        result.impostor = std::move(frame);
        result.triangles_impostor = result.impostor_stats.chunk_triangles + result.impostor_stats.far_triangles;
      } catch (const std::exception& e) {
        const std::int64_t id = cell->id;
        result.fallback_reason = "cell " + std::to_string(id) + ": " + e.what();
        failures_[id] = result.fallback_reason;
        decoded_.erase(id);
        if (warn) std::fprintf(warn, "warning: %s; drawing ground truth there\n", result.fallback_reason.c_str());
      }
    }
    result.fallback = !result.impostor.has_value();
  }
  if (want_truth || result.fallback) {
    ViewFrame frame;
    drawer_->draw_truth(camera, r.width, r.height, options, frame);  // warm-up: uploads
    result.truth_stats = drawer_->draw_truth(camera, r.width, r.height, options, frame);
    result.triangles_truth = result.truth_stats.chunk_triangles;
    result.truth = std::move(frame);
  }
  if (result.fallback) {
    result.impostor = result.truth;
    result.impostor_stats = result.truth_stats;
    result.triangles_impostor = result.triangles_truth;
  }
  if (mode == ViewMode::diff) result.metrics = compare_frames(*result.impostor, *result.truth);
  return result;
}

}  // namespace cellbake
