#include "runner/walk/walk_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <utility>

#include "viewer/frame_log.h"

namespace cellbake {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

std::string num(double v, const char* format = "%.2f") {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[48];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

double percentile(std::vector<double> values, double p) {
  return values.empty() ? kNaN : nearest_rank_percentile(std::move(values), p);
}

WalkSummary summarise_walk(const std::vector<WalkFrame>& frames, double fps) {
  WalkSummary s;
  s.frames = frames.size();
  s.fps = fps;
  s.seconds = fps > 0 ? double(frames.size()) / fps : 0;
  std::vector<double> psnr, frame_ms, truth_ms, switch_ms;
  std::set<std::int64_t> distinct;
  for (const WalkFrame& f : frames) {
    frame_ms.push_back(f.frame_ms);
    truth_ms.push_back(f.truth_ms);
    if (f.cell_switch) {
      ++s.cell_switches;
      switch_ms.push_back(f.frame_ms);
    }
    if (s.cells_visited.empty() || f.cell_switch) s.cells_visited.push_back(f.cell);
    distinct.insert(f.cell);
    if (f.fallback) {
      ++s.fallback_frames;
      continue;
    }
    psnr.push_back(f.psnr_db);
    if (s.worst_frame < 0 || f.psnr_db < s.psnr_worst_db) s.worst_frame = f.index, s.psnr_worst_db = f.psnr_db;
  }
  s.distinct_cells = distinct.size();
  s.psnr_median_db = median(psnr);
  s.frame_ms_median = median(frame_ms);
  s.frame_ms_p99 = percentile(frame_ms, 99);
  s.frame_ms_max = frame_ms.empty() ? kNaN : *std::max_element(frame_ms.begin(), frame_ms.end());
  s.truth_ms_median = median(truth_ms);
  s.switch_frame_ms_median = median(switch_ms);
  return s;
}

nlohmann::json walk_summary_json(const WalkSummary& s) {
  return {{"frames", s.frames},
          {"fps", s.fps},
          {"seconds", s.seconds},
          {"psnr_db",
           {{"median", number_or_null(s.psnr_median_db)},
            {"median_infinite", std::isinf(s.psnr_median_db)},
            {"worst", number_or_null(s.psnr_worst_db)},
            {"worst_frame", s.worst_frame}}},
          {"frame_ms",
           {{"median", number_or_null(s.frame_ms_median)},
            {"p99", number_or_null(s.frame_ms_p99)},
            {"max", number_or_null(s.frame_ms_max)}}},
          {"truth_ms_median", number_or_null(s.truth_ms_median)},
          {"switch_frame_ms_median", number_or_null(s.switch_frame_ms_median)},
          {"cells_visited", s.cells_visited},
          {"distinct_cells", s.distinct_cells},
          {"cell_switches", s.cell_switches},
          {"fallback_frames", s.fallback_frames},
          {"video", s.video},
          {"frames_dir", s.frames_dir},
          {"plot", s.plot},
          {"encoder", s.encoder},
          {"note", s.note},
          {"wall_seconds", s.wall_seconds}};
}

std::string walk_summary_text(const WalkSummary& s) {
  std::ostringstream o;
  o << s.frames << " frames (" << num(s.seconds, "%.1f") << " s at " << num(s.fps, "%.4g") << " fps) through "
    << s.distinct_cells << " cells, " << s.cell_switches << " cell switches";
  if (s.fallback_frames) o << ", " << s.fallback_frames << " frames drawn as truth (cell missing or failed)";
  o << "\nPSNR median " << num(s.psnr_median_db) << " dB, worst " << num(s.psnr_worst_db) << " dB (frame "
    << s.worst_frame << ")\ncells frame time median " << num(s.frame_ms_median, "%.1f") << " ms, p99 "
    << num(s.frame_ms_p99, "%.1f") << " ms, max " << num(s.frame_ms_max, "%.1f") << " ms (median at a cell switch "
    << num(s.switch_frame_ms_median, "%.1f") << " ms); truth median " << num(s.truth_ms_median, "%.1f")
    << " ms\ncells visited:";
  for (const std::int64_t id : s.cells_visited) o << " " << id;
  o << "\n";
  if (!s.video.empty()) o << "video: " << s.video << " (" << s.encoder << ")\n";
  if (!s.frames_dir.empty()) o << "frames: " << s.frames_dir << "/ (PNG)\n";
  if (!s.note.empty()) o << "note: " << s.note << "\n";
  if (!s.plot.empty()) o << "plot: " << s.plot << "\n";
  if (s.wall_seconds > 0) o << "rendered in " << num(s.wall_seconds, "%.1f") << " s\n";
  return o.str();
}

std::string walk_frames_csv(const std::vector<WalkFrame>& frames) {
  std::ostringstream o;
  o << "frame,t,eye_x,eye_y,eye_z,look_x,look_y,look_z,cell,cell_switch,fallback,psnr_db,ssim,hole_fraction,load_ms,"
       "draw_ms,frame_ms,truth_ms,triangles,truth_triangles\n";
  for (const WalkFrame& f : frames)
    o << f.index << "," << num(f.t, "%.4f") << "," << num(f.eye.x, "%.6g") << "," << num(f.eye.y, "%.6g") << ","
      << num(f.eye.z, "%.6g") << "," << num(f.look.x, "%.6g") << "," << num(f.look.y, "%.6g") << ","
      << num(f.look.z, "%.6g") << "," << f.cell << "," << (f.cell_switch ? 1 : 0) << "," << (f.fallback ? 1 : 0)
      << "," << num(f.psnr_db, "%.4f") << "," << num(f.ssim, "%.5f") << "," << num(f.hole_fraction, "%.6f") << ","
      << num(f.load_ms, "%.3f") << "," << num(f.draw_ms, "%.3f") << "," << num(f.frame_ms, "%.3f") << ","
      << num(f.truth_ms, "%.3f") << "," << f.triangles << "," << f.truth_triangles << "\n";
  return o.str();
}

}  // namespace cellbake
