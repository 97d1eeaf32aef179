// A stored face image compared with the model it shows (issue #37, item 3):
// the one damage nothing else in a cell can tell apart is a valid image of the
// right format and size in a face's place (a PNG of zeros, another face's
// image), its content hash restamped. Against the model it stands out: the
// cube map is sampled again at the sample's eye, one ray per pixel at a
// fraction of the face size, and the texels the face's mesh reads are compared
// with it. Used by check_cell (storage/cell_check.h) when its context can
// resample the model.
#pragma once

#include <functional>
#include <string>

#include "stages/cube_map.h"
#include "storage/cell_db.h"

namespace cellbake {

// The cube map of what cell `row`'s far field shows from `eye`, `face_size`
// pixels per face edge (CubeSampler::sample with the bake's discard box and
// shading, one ray per pixel).
using FarFieldResampler = std::function<CubeSample(const CellRow& row, const Vec3d& eye, int face_size)>;

// At most this many pixels per face edge are resampled (a divisor of the face size).
constexpr int kImageCheckMaxResample = 64;
// A face image is wrong when its mean colour at the compared pixels differs
// from the model's by more than this (0..255, in any of red, green, blue)
// over at least kImageCheckMinPixels pixels. Means forgive what single pixels
// may differ by: lossy codecs, supersampling, thin geometry and mip levels.
constexpr double kImageCheckMaxMeanDifference = 64.0;
constexpr int kImageCheckMinPixels = 32;

// The resample size for face images of `face_size` pixels: its largest divisor
// at most kImageCheckMaxResample.
int image_check_resample_size(int face_size);

// Every face image of done cell `row` (decodable: check_cell has decoded it)
// against `resample`: one cube per sample with images, at
// image_check_resample_size; per face, the image bilinearly filtered at each
// resampled pixel's centre (as the viewer reads it) where the pixel holds a
// surface and the face's mesh reads all four texels (stages/texel_footprint.h).
// Empty when sound, else e.g. "sample 2 face 3 image: mean colour (0, 0, 0) at
// 212 pixels its mesh reads, the model shows (180, 171, 160) there".
// Throws what `resample` throws.
std::string check_face_images_against_model(const CellRow& row, const FarFieldResampler& resample);

}  // namespace cellbake
