// The verify report's walk section: the short walk `verify --walk-seconds`
// renders through the verified cells (runner/walk/walk_runner.h), shown as
// its video (linked and embedded as a <video>, or its PNG frames linked),
// its worst frame, its plot of PSNR and frame time and its summary. Pure:
// the caller reads the files.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace cellbake {

struct VerifyWalkSection {
  // Paths relative to the report folder ("" when not written).
  std::string video;       // the MP4
  std::string frames_dir;  // PNG frames instead of a video (no ffmpeg)
  std::string plot;        // the SVG plot
  std::string worst_png;   // the worst frame as a triptych
  std::string summary_text;
  nlohmann::json summary;  // walk_summary_json, also stored in report.json under "walk"
  std::string error;       // non-empty: the walk failed, and why
};

// The section's HTML: a heading, then the video (a <video> element and a
// link) or a link to the frames, the worst frame as <img src=worst_data_uri>
// (left out when empty), `plot_svg` inline (from its <svg on; left out when
// empty) and the summary; or the error. Deterministic.
std::string walk_section_html(const VerifyWalkSection& walk, const std::string& worst_data_uri,
                              const std::string& plot_svg);

}  // namespace cellbake
