// Three equally sized frames side by side: truth | cells (impostor) |
// difference image, the picture `verify` shows for its worst views and
// `walk` encodes frame by frame. Pure code over pixel arrays.
#pragma once

#include <vector>

#include "stages/geometry.h"
#include "viewer/image_metrics.h"

namespace cellbake {

// Pixel width of the triptych of three `panel_width` wide panels with
// `gap` pixels between neighbouring panels: 3 * panel_width + 2 * gap.
int triptych_width(int panel_width, int gap = 0);

// truth | impostor | diff, left to right, row-major (row 0 at the top),
// triptych_width(w, gap) x h pixels; the gaps are filled with `gap_color`.
// `diff` holds w * h pixels (error_image). Throws std::invalid_argument when
// the three do not share one size or gap < 0.
std::vector<Rgba8> triptych(const ViewFrame& truth, const ViewFrame& impostor, const std::vector<Rgba8>& diff,
                            int gap = 0, Rgba8 gap_color = {255, 255, 255, 255});

// The same image as packed 8-bit RGB bytes (3 per pixel, alpha dropped), the
// raw frame layout a video encoder reads (ffmpeg -pix_fmt rgb24).
std::vector<unsigned char> rgb24(const std::vector<Rgba8>& pixels);

}  // namespace cellbake
