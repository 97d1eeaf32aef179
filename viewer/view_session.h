// A headless viewing session over one cell database: finds the view cell of an
// eye, decodes its far field (falling back to ground truth, with a warning,
// when the cell is missing, failed or corrupt), and renders impostor and/or
// ground-truth frames on an offscreen context (OSMesa when the build has it,
// else EGL: create_headless_gl_context). A session over a geometry store
// alone (StoreOnly) draws ground truth only: a model looked at before baking.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "viewer/cell_index.h"
#include "viewer/decoded_cell.h"
#include "viewer/image_metrics.h"
#include "viewer/scene_drawer.h"

namespace cellbake {

enum class ViewMode { impostor, truth, diff };

// Parses "impostor" | "truth" | "diff"; throws std::invalid_argument otherwise.
ViewMode parse_view_mode(const std::string& text);

struct ViewRequest {
  Vec3d eye, look;
  double fov_y_deg = 60;
  int width = 512, height = 512;
  double near_plane = 0.05;
  std::optional<std::int64_t> cell;  // force this cell instead of the eye's
  // Which samples' far field to draw (viewer/sample_selection.h): far-field
  // triangles per view (unset: the database's view.far_budget) and a cap.
  std::optional<std::uint64_t> far_budget;
  int max_samples = 0;
};

struct ViewResult {
  std::int64_t cell_id = 0;  // the eye's (or the forced) cell; 0 when the database has no cells
  bool fallback = false;     // the impostor was replaced by ground truth
  std::string fallback_reason;
  std::optional<ViewFrame> impostor, truth;  // as the mode asks
  SceneFrameStats impostor_stats, truth_stats;
  std::uint64_t triangles_impostor = 0;  // the cell's near triangles (inside the cull box) + far triangles drawn
  std::uint64_t triangles_truth = 0;     // chunk triangles submitted for the truth
  std::optional<ImageMetrics> metrics;   // diff mode
};

// Tag for ViewSession's store-only constructor.
struct StoreOnly {};

class ViewSession {
 public:
  // Opens `database` and the geometry store its meta `store` names (or
  // `store_override`). Throws std::runtime_error naming the file when either
  // cannot be opened or the meta is missing.
  explicit ViewSession(const std::filesystem::path& database, const std::filesystem::path& store_override = {});
  // Opens the geometry store `store` alone: render() draws truth frames only
  // (ViewMode::truth; other modes throw std::invalid_argument), up axis = the
  // store's recorded one (z when not recorded), default shading. Throws
  // std::runtime_error naming the file when it is not a geometry store.
  ViewSession(StoreOnly, const std::filesystem::path& store);
  ~ViewSession();

  // Renders one view. Warnings (cell fallback) go to `warn` (e.g. stderr).
  // Each frame is rendered twice and the second, warm pass (everything
  // uploaded) is timed. Throws on bad requests and GL failures.
  ViewResult render(const ViewRequest& request, ViewMode mode, std::FILE* warn);

  const CellIndex& cells() const { return index_; }
  const Vec3d& up() const { return up_; }
  const GeometryStore& store() const { return *store_; }
  // "" when the store is the one the database was baked from (meta
  // `store_hash`) or a store-only session; else a sentence naming both
  // (storage/store_check.h store_mismatch).
  std::string store_mismatch() const;
  bool store_only() const { return !db_; }

 private:
  // The decoded cell, or nullptr with `reason` set (cached either way).
  const DecodedCell* load_cell(std::int64_t id, std::string& reason, std::FILE* warn);

  std::unique_ptr<CellDb> db_;  // null in a store-only session
  std::unique_ptr<GeometryStore> store_;
  CellIndex index_;
  Vec3d up_;
  std::uint64_t far_budget_;  // the database's view.far_budget (or the default)
  std::unique_ptr<SceneDrawer> drawer_;
  std::map<std::int64_t, std::shared_ptr<const DecodedCell>> decoded_;
  std::map<std::int64_t, std::string> failures_;
};

// A default view of a model with bounds `bounds` and up axis `up` (unit +z or
// +y): from outside the bounds (one bounding-box diagonal from the centre,
// above it and off two horizontal axes), looking at the centre, so that the
// whole model fits a 60 degree field of view. Sets eye and look of `request`.
void default_overview(const Box3d& bounds, const Vec3d& up, ViewRequest& request);

}  // namespace cellbake
