// The walk's plot: PSNR (top panel) and the cells frame time (bottom panel,
// with the truth's in grey) against walk time, one shared time axis, every
// cell switch marked by a dashed vertical line labelled with the cell
// entered. SVG text; pure code (no files).
#pragma once

#include <string>
#include <vector>

#include "runner/walk/walk_summary.h"

namespace cellbake {

// A complete SVG document, `width` pixels wide. Frames with an infinite PSNR
// (drawn exactly: nothing approximated) are drawn at the top of the PSNR
// axis as hollow markers; fallback frames (no cell) are left out of the
// PSNR line. Polylines have class "psnr", "frame-ms" and "truth-ms"; switch
// lines class "switch" with a <title> naming the cell and frame.
// Deterministic. An empty walk gives axes saying "no frames".
std::string walk_plot_svg(const std::vector<WalkFrame>& frames, const std::string& title, int width = 900);

}  // namespace cellbake
