// What a walk measured: one record per frame (where the eye was, which cell
// drew it, the error against the truth, how long the cells frame took) and
// the walk's summary (frames, median and worst PSNR, frame time median / p99 /
// max, the cells visited in order) as JSON, text and a per-frame CSV. Pure.
#pragma once

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct WalkFrame {
  int index = 0;
  double t = 0;  // walk time, seconds (index / fps)
  Vec3d eye, look;
  std::int64_t cell = 0;     // the cell whose impostor drew the frame (the eye's, viewer/cell_index.h nearest)
  bool cell_switch = false;  // another cell than the previous frame's (never the first frame)
  bool fallback = false;     // the cell could not be drawn: the truth stands in (PSNR infinite)
  double psnr_db = 0, ssim = 0, hole_fraction = 0;
  // The cells frame as a viewer would draw it: reading and decoding the cell
  // when the eye enters it (load), then drawing (uploads included) and
  // reading back (draw); frame = load + draw. Wall clock, milliseconds.
  double load_ms = 0, draw_ms = 0, frame_ms = 0;
  double truth_ms = 0;  // the truth frame (drawn ahead on another thread)
  std::uint64_t triangles = 0;  // the cells frame's triangles
  std::uint64_t truth_triangles = 0;  // the truth frame's chunk triangles drawn (hidden chunks skipped)
};

// Nearest-rank percentile (p in [0, 100]) of `values` (viewer/frame_log.h
// nearest_rank_percentile); NaN when empty.
double percentile(std::vector<double> values, double p);

struct WalkSummary {
  std::size_t frames = 0;
  double fps = 0, seconds = 0;  // walk time: frames / fps
  double psnr_median_db = std::numeric_limits<double>::quiet_NaN();  // over frames drawn by cells (not fallback)
  double psnr_worst_db = std::numeric_limits<double>::quiet_NaN();
  int worst_frame = -1;
  double frame_ms_median = std::numeric_limits<double>::quiet_NaN();
  double frame_ms_p99 = std::numeric_limits<double>::quiet_NaN();
  double frame_ms_max = std::numeric_limits<double>::quiet_NaN();
  double truth_ms_median = std::numeric_limits<double>::quiet_NaN();
  double switch_frame_ms_median = std::numeric_limits<double>::quiet_NaN();  // frames that entered a cell
  std::vector<std::int64_t> cells_visited;  // in the order entered (a cell entered twice listed twice)
  std::size_t distinct_cells = 0, cell_switches = 0, fallback_frames = 0;
  // Set by the runner: what was written and how long it took.
  std::string video, frames_dir, plot, encoder, note;
  double wall_seconds = 0;
};

// The statistics of `frames` (frame time over every frame, PSNR over frames
// not drawn as fallback; ties for the worst go to the first). Deterministic.
WalkSummary summarise_walk(const std::vector<WalkFrame>& frames, double fps);

// {frames, fps, seconds, psnr_db {median, worst, worst_frame}, frame_ms
// {median, p99, max}, truth_ms_median, switch_frame_ms_median, cells_visited,
// distinct_cells, cell_switches, fallback_frames, video, frames_dir, plot,
// encoder, note, wall_seconds}; non-finite numbers as null.
nlohmann::json walk_summary_json(const WalkSummary& s);
// A few lines for people (also printed by `cellbake walk`).
std::string walk_summary_text(const WalkSummary& s);
// Header line, then one line per frame.
std::string walk_frames_csv(const std::vector<WalkFrame>& frames);

}  // namespace cellbake
