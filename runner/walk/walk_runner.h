// `cellbake walk`: a camera path through a cell database — read from a file
// (the `render --path` format) or made through every selected cell
// (runner/walk/walk_path.h) — drawn frame by frame as truth | cells |
// difference (viewer/triptych.h), the truth one frame ahead on a second
// thread (runner/walk/truth_ahead.h); the frames go to an MP4 through the
// ffmpeg program (runner/walk/video_writer.h), or to PNG files when it is
// absent or not wanted; plus the plot of PSNR and frame time along the path
// (runner/walk/walk_plot.h) and the summary (runner/walk/walk_summary.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "runner/walk/walk_summary.h"

namespace cellbake {

struct WalkOptions {
  std::filesystem::path store;      // geometry store override ("" = the database's meta `store`)
  std::filesystem::path path_file;  // camera path file; "" = the automatic walk
  std::string cells;                // automatic walk: cell selection like "1-20" ("" = every done cell)
  double seconds = 0;               // at most this long (0: the whole path)
  double fps = 24;                  // frames per second of walk time (the video's rate)
  double speed = 1.4;               // automatic walk: model units (metres) per second
  int width = 320, height = 240;    // each of the three panels, pixels
  double fov_y_deg = 60;
  double near_plane = 0.05;  // model units
  bool video = true;         // false: PNG frames even when ffmpeg is present
  bool truth_ahead = true;   // draw the truth of the next frame on a second thread
  bool skip_hidden_truth = true;  // SceneDrawOptions::truth_occlusion_culling
  bool quiet = false;        // no progress output
  std::filesystem::path write_path;  // write the camera path here (the --path format) and draw nothing
};

// Files in the output folder: walk.mp4 (or frames/frame_NNNN.png), walk.svg
// (the plot), walk.json and walk.txt (the summary), walk.csv (per frame),
// worst.png (the frame of the worst PSNR as a triptych).
struct WalkResult {
  WalkSummary summary;
  std::vector<WalkFrame> frames;
  std::filesystem::path dir, video, frames_dir, plot, json, text, csv, worst_png;
};

// Walks `database` into `out_dir` (created). Throws std::runtime_error or
// std::invalid_argument naming the file or option for setup errors (database
// or store cannot be opened, a malformed path file, no cell selected, an
// output that would overwrite an input). A cell that cannot be drawn is
// replaced by the truth (a warning naming it; frames counted as fallback).
// Frame images and PSNR do not depend on truth_ahead; timings do. With
// `write_path`, only the camera path is written there (no folder, no frames;
// the result's summary counts its frames).
WalkResult run_walk(const std::filesystem::path& database, const std::filesystem::path& out_dir,
                    const WalkOptions& options);

}  // namespace cellbake
