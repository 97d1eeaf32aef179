#include "viewer/frame_log.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cellbake {

double nearest_rank_percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size()));
  return values[static_cast<std::size_t>(std::max(rank, 1.0)) - 1];
}

FrameSummary summarize_frames(const std::vector<FrameRecord>& frames, std::uint64_t cache_cap_bytes, int window) {
  FrameSummary s;
  s.frames = frames.size();
  s.cache_cap_bytes = cache_cap_bytes;
  std::vector<double> ms;
  int last_switch = -1;
  for (const FrameRecord& f : frames) {
    ms.push_back(f.frame_ms);
    if (f.switched) {
      ++s.switches;
      last_switch = f.frame;
    }
    if (f.drawn_cell != f.cell_id) ++s.lagging_frames;
    if (s.max_frame < 0 || f.frame_ms > s.max_ms) s.max_ms = f.frame_ms, s.max_frame = f.frame;
    if (last_switch >= 0 && f.frame - last_switch <= window &&
        (s.worst_near_switch_frame < 0 || f.frame_ms > s.worst_near_switch_ms))
      s.worst_near_switch_ms = f.frame_ms, s.worst_near_switch_frame = f.frame;
    s.cache_peak_bytes = std::max(s.cache_peak_bytes, f.cache_bytes);
    s.upload_bytes += f.upload_bytes;
  }
  s.median_ms = nearest_rank_percentile(ms, 50);
  s.p99_ms = nearest_rank_percentile(ms, 99);
  return s;
}

std::string frame_log_csv(const std::vector<FrameRecord>& frames) {
  std::string text = "frame,cell,drawn_cell,switched,frame_ms,draw_ms,upload_ms,upload_bytes,cache_bytes,triangles,far_geometry_triangles,"
      "chunk_budget\n";
  char line[256];
  for (const FrameRecord& f : frames) {
    std::snprintf(line, sizeof line, "%d,%lld,%lld,%d,%.3f,%.3f,%.3f,%llu,%llu,%llu,%llu,%llu\n", f.frame, (long long)f.cell_id,
                  (long long)f.drawn_cell, f.switched ? 1 : 0, f.frame_ms, f.draw_ms, f.upload_ms,
                  (unsigned long long)f.upload_bytes, (unsigned long long)f.cache_bytes,
                  (unsigned long long)f.triangles, (unsigned long long)f.far_geometry_triangles,
                  (unsigned long long)f.chunk_budget);
    text += line;
  }
  return text;
}

std::string frame_summary_text(const FrameSummary& s) {
  char text[1024];
  std::snprintf(text, sizeof text,
                "walk summary:\n"
                "  frames: %zu\n"
                "  switches: %zu\n"
                "  frames drawn from the previous cell: %zu\n"
                "  frame ms: median %.1f, p99 %.1f, max %.1f (frame %d)\n"
                "  p99 / median: %.2f\n"
                "  worst frame near a switch: %.1f ms (frame %d)\n"
                "  uploaded: %.1f MB\n"
                "  cache MB: peak %.1f, cap %.1f\n",
                s.frames, s.switches, s.lagging_frames, s.median_ms, s.p99_ms, s.max_ms, s.max_frame,
                s.median_ms > 0 ? s.p99_ms / s.median_ms : 0.0, s.worst_near_switch_ms, s.worst_near_switch_frame,
                s.upload_bytes / 1048576.0, s.cache_peak_bytes / 1048576.0, s.cache_cap_bytes / 1048576.0);
  return text;
}

}  // namespace cellbake
