// Image-space comparison of an impostor rendering (near field + textured depth
// meshes) against the ground truth from the same camera: colour error (PSNR,
// SSIM), coverage errors (holes, skins) and depth error. Pure code over plain
// frames: no GL, no files. Wilson 2002 (ch. 7) judges its impostors by exactly
// these failure modes: missing surfaces (holes) and surfaces at a wrong depth
// stretched across depth discontinuities (skins).
#pragma once

#include <cstdint>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

// One rendered view: row-major, row 0 at the top, width * height pixels.
// `depth` is planar view depth in model units, +infinity where nothing was drawn.
struct ViewFrame {
  int width = 0, height = 0;
  std::vector<Rgba8> color;
  std::vector<float> depth;
  bool covered(std::size_t i) const;  // finite depth at pixel i
};

struct ImageMetricsParams {
  // A pixel is a skin when both frames are covered and the impostor is nearer
  // than the truth by more than this fraction of the truth's depth.
  double skin_relative_depth = 0.05;
};

// Every metric compares `impostor` with `truth` pixel by pixel. Definitions:
//  * psnr_db: 10 log10(255^2 / MSE), MSE over the R, G, B channels of the
//    pixels covered in either frame (background counts as black there);
//    +infinity when that MSE is 0 or no pixel is covered in either frame.
//  * ssim: mean SSIM (Wang et al. 2004) over every 8x8 window (stride 1, uniform
//    weights) of Rec.601 luminance Y = 0.299 R + 0.587 G + 0.114 B, with
//    C1 = (0.01 * 255)^2, C2 = (0.03 * 255)^2, over the whole image; 1 when
//    identical. Images smaller than 8 on a side use one window over all of it.
//  * hole_fraction: among pixels covered in the truth, the fraction not
//    covered in the impostor (0 when the truth covers nothing).
//  * skin_fraction: among pixels covered in the truth, the fraction where the
//    impostor is covered and nearer: (d_truth - d_impostor) / d_truth >
//    params.skin_relative_depth.
//  * depth_error_median: median of |d_impostor - d_truth| / d_truth over pixels
//    covered in both (0 when none). For an even count, the mean of the two middle values.
//  * extra_fraction: among pixels not covered in the truth, the fraction the
//    impostor covers (surfaces where there should be sky).
// Deterministic. Throws std::invalid_argument when the frames differ in size
// or their vectors do not hold width * height values.
struct ImageMetrics {
  double psnr_db = 0;
  double ssim = 0;
  double hole_fraction = 0;
  double skin_fraction = 0;
  double depth_error_median = 0;
  double extra_fraction = 0;
  std::uint64_t truth_covered_pixels = 0;
};
ImageMetrics compare_frames(const ViewFrame& impostor, const ViewFrame& truth, const ImageMetricsParams& params = {});

// Mean SSIM as compare_frames defines it (8x8 uniform windows at stride 1 of
// Rec.601 luminance, the same C1 and C2), averaged over only the windows whose
// every pixel has mask != 0: e.g. a cube face's covered pixels, so that a
// background fill (or sky) neither helps nor hurts. `a`, `b` and `mask` are
// row-major width x height; images smaller than 8 on a side have the one
// window over all of it. Returns NaN when no window lies wholly inside the
// mask. Pure, deterministic. Throws std::invalid_argument when a size is < 1
// or a vector does not hold width * height values.
double masked_ssim(const std::vector<Rgba8>& a, const std::vector<Rgba8>& b, int width, int height,
                   const std::vector<std::uint8_t>& mask);

// True when `frame` shows nothing to compare: no pixel is covered, or every
// covered pixel has the same R, G, B (a black or single-colour model, an
// empty view). PSNR against such a truth says nothing about what a person
// would see (a black truth and a black impostor give +infinity). Pure; the
// uncovered background is ignored. Throws std::invalid_argument like
// compare_frames for a frame whose vectors do not hold width * height values.
bool is_blank(const ViewFrame& frame);

// `frame` box-filtered down by `factor` on each axis (a supersampled render
// to the size it stands for): each pixel the mean colour of its factor^2
// pixels (background included, rounded), and the nearest of their depths
// (covered when any of them is). Sizes not divisible by `factor` lose the
// last partial row and column. Throws std::invalid_argument when `factor` < 1
// or the frame is smaller than `factor` on a side.
ViewFrame box_downsample(const ViewFrame& frame, int factor);

// A false-colour error image of the same size (row 0 at the top):
//  * covered in neither frame: black;
//  * hole (truth covered, impostor not): magenta (255, 0, 255);
//  * skin (as in compare_frames): yellow (255, 255, 0);
//  * extra surface (impostor covered, truth not): cyan (0, 255, 255);
//  * otherwise the colour error e = max over R, G, B of |difference| / 255,
//    drawn on a linear ramp dark blue (0, 0, 64) at e = 0 -> green (0, 255, 0)
//    at e = 0.25 -> red (255, 0, 0) at e >= 0.5.
// Alpha is 255 everywhere. Same validation as compare_frames.
std::vector<Rgba8> error_image(const ViewFrame& impostor, const ViewFrame& truth, const ImageMetricsParams& params = {});

}  // namespace cellbake
