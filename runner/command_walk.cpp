// `cellbake walk CELLS.db [--store S] [--path FILE | --auto] [--cells SEL]
//  [--seconds N] [--fps F] [--speed V] [--size WxH] [--no-video] --out DIR`:
// a walk through the bake as a truth | cells | difference video with a plot
// of PSNR and frame time along the path and a summary
// (runner/walk/walk_runner.h); `--write-path FILE` instead of `--out` writes
// the walk's camera path only.
#include <CLI/CLI.hpp>

#include <cstdio>

#include "runner/commands.h"
#include "runner/console.h"
#include "runner/walk/walk_runner.h"
#include "viewer/camera_path.h"

namespace cellbake {

void add_walk_command(CLI::App& app) {
  struct Options {
    std::string database, out, size = "320x240";
    bool auto_path = false, json = false, no_video = false, serial = false, draw_hidden = false;
    WalkOptions walk;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "walk", "Walk through the bake: a truth | cells | difference video (MP4), a plot of PSNR and frame time "
              "along the path, a summary");
  cmd->add_option("database", opt->database, "Cell database")->required();
  CLI::Option* out = cmd->add_option(
      "--out,-o", opt->out, "Output folder: walk.mp4 (or frames/*.png), walk.svg, walk.json, walk.txt, walk.csv, worst.png");
  CLI::Option* write_path = cmd->add_option(
      "--write-path", opt->walk.write_path,
      "Write the walk's camera path to this file (the --path format, e.g. for cellbake-view --path) and draw nothing");
  out->excludes(write_path);
  cmd->add_option("--store", opt->walk.store, "Geometry store (default: the one the database names)");
  CLI::Option* path = cmd->add_option("--path", opt->walk.path_file,
                                      "Camera path file, one frame per line: \"ex ey ez lx ly lz\" (as render --path)");
  CLI::Option* autop = cmd->add_flag(
      "--auto", opt->auto_path,
      "Make the path (the default): through every selected cell in serpentine order at eye height, at walking "
      "speed, smooth turns");
  path->excludes(autop);
  cmd->add_option("--cells", opt->walk.cells, "Automatic path: walk through these cells, e.g. 1-20 (default: all done)");
  cmd->add_option("--seconds", opt->walk.seconds, "Walk at most this long (0 = the whole path)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--fps", opt->walk.fps, "Frames per second of walk time")
      ->check(CLI::Range(1.0, 240.0))
      ->capture_default_str();
  cmd->add_option("--speed", opt->walk.speed, "Automatic path: walking speed, model units (metres) per second")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--size", opt->size, "Size of each of the three panels, WxH")->capture_default_str();
  cmd->add_option("--fov", opt->walk.fov_y_deg, "Vertical field of view, degrees")
      ->check(CLI::Range(1.0, 179.0))
      ->capture_default_str();
  cmd->add_option("--near", opt->walk.near_plane, "Near plane distance, model units")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--no-video", opt->no_video, "Write PNG frames instead of an MP4 (also when ffmpeg is absent)");
  cmd->add_flag("--serial", opt->serial,
                "Draw the truth on the same thread as the cells (default: the next frame's truth on a second thread)");
  cmd->add_flag("--draw-hidden", opt->draw_hidden,
                "Draw every truth chunk in view, also those hidden behind nearer ones (default: skip them; the "
                "same frames except where surfaces tie exactly in depth)");
  cmd->add_flag("--json", opt->json, "Print the summary as JSON");
  cmd->callback([opt] {
    if (opt->out.empty() && opt->walk.write_path.empty())
      throw CLI::RequiredError("--out (or --write-path)");
    std::tie(opt->walk.width, opt->walk.height) = parse_image_size(opt->size);
    opt->walk.video = !opt->no_video;
    opt->walk.truth_ahead = !opt->serial;
    opt->walk.skip_hidden_truth = !opt->draw_hidden;
    opt->walk.quiet = quiet_output();
    const WalkResult r = run_walk(opt->database, opt->out, opt->walk);
    if (!opt->walk.write_path.empty()) {
      std::printf("camera path: %zu views written to %s\n", r.summary.frames, opt->walk.write_path.c_str());
      return;
    }
    if (opt->json) {
      nlohmann::json j = walk_summary_json(r.summary);
      j["dir"] = r.dir.string();
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("%s", walk_summary_text(r.summary).c_str());
    std::printf("written to %s\n", r.dir.c_str());
  });
}

}  // namespace cellbake
