// The interactive viewer's scripted-walk log (cellbake-view --path
// --frame-log): one record per frame (whole frame time, the eye's cell and
// the cell drawn, cell switches, GPU uploads, decoded-cell cache bytes) as
// CSV, and a summary of frame times around cell switches. Pure: no files, no GL.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cellbake {

struct FrameRecord {
  int frame = 0;
  std::int64_t cell_id = 0;     // the eye's cell (0: outside every cell)
  std::int64_t drawn_cell = 0;  // the cell whose impostor was drawn (0: ground truth)
  bool switched = false;        // the eye's cell differs from the previous frame's (never on frame 0)
  double frame_ms = 0;          // the whole frame, input to buffer swap: what the user waits for
  double draw_ms = 0;           // of it, drawing and reading back the view
  double upload_ms = 0;         // of it, GPU uploads ahead of drawing and of faces at the draw
  std::uint64_t upload_bytes = 0;  // bytes uploaded to the GPU during the frame (faces and chunks)
  std::uint64_t cache_bytes = 0;   // decoded cells held by the cache after the frame
  std::uint64_t triangles = 0;     // submitted by the draw: chunks (near field, far geometry) and depth meshes
  std::uint64_t far_geometry_triangles = 0;  // of those, exact far geometry
  std::uint64_t chunk_budget = 0;            // chunk triangles the frame time budget allowed (0: no limit)
};

struct FrameSummary {
  std::size_t frames = 0;
  std::size_t switches = 0;        // frames whose eye entered another cell
  std::size_t lagging_frames = 0;  // frames that drew another cell than the eye's (its upload not complete)
  double median_ms = 0, p99_ms = 0, max_ms = 0;  // frame_ms, nearest rank
  int max_frame = -1;
  double worst_near_switch_ms = 0;  // the longest frame from a switch to `window` frames after it
  int worst_near_switch_frame = -1;
  std::uint64_t cache_peak_bytes = 0, cache_cap_bytes = 0;
  std::uint64_t upload_bytes = 0;  // over every frame
};

// Nearest-rank percentile (p in [0, 100]) of `values`; 0 when empty.
double nearest_rank_percentile(std::vector<double> values, double p);

// Summarises `frames`; `window` frames after each switch count as near it.
FrameSummary summarize_frames(const std::vector<FrameRecord>& frames, std::uint64_t cache_cap_bytes, int window = 10);

// "frame,cell,drawn_cell,switched,frame_ms,draw_ms,upload_ms,upload_bytes,cache_bytes,triangles,
// far_geometry_triangles,chunk_budget" and one line per record.
std::string frame_log_csv(const std::vector<FrameRecord>& frames);

// The summary as "key: value" lines under "walk summary:" (what the tests parse).
std::string frame_summary_text(const FrameSummary& s);

}  // namespace cellbake
