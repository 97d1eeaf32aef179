#include "storage/face_image_check.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "stages/encode/encode.h"
#include "stages/texel_footprint.h"

namespace cellbake {

int image_check_resample_size(int face_size) {
  if (face_size <= kImageCheckMaxResample) return std::max(face_size, 1);
  for (int step = (face_size + kImageCheckMaxResample - 1) / kImageCheckMaxResample; step < face_size; ++step)
    if (face_size % step == 0) return face_size / step;
  return 1;
}

namespace {

std::string rgb_text(const std::array<double, 3>& c) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.0f, %.0f, %.0f)", c[0], c[1], c[2]);
  return buf;
}

// The problem with one face's image against the resampled face `model`, or "".
std::string compare_face(const FaceRow& f, const DecodedImage& image, const CubeFace& model, const std::string& at) {
  const int size = image.width;
  if (size < 1 || image.height != size || model.size < 1 || size % model.size != 0) return "";
  const int step = size / model.size;
  const std::vector<std::uint8_t> read = texels_read_by(decode_face_mesh(f.mesh), size);
  // The resampled pixel's centre lies at image position c = (i + 0.5) * step
  // (texel centres at j + 0.5): between texels c - 1 and c for an even step,
  // on texel (c - 0.5) for an odd one.
  const int lo = step % 2 == 0 ? step / 2 - 1 : step / 2, hi = step / 2;
  std::array<double, 3> stored{}, seen{};
  int pixels = 0;
  for (int y = 0; y < model.size; ++y)
    for (int x = 0; x < model.size; ++x) {
      const std::size_t m = std::size_t(y) * model.size + x;
      if (!std::isfinite(model.depth[m])) continue;  // kBackgroundDepth: nothing there
      const std::size_t t00 = std::size_t(y * step + lo) * size + std::size_t(x * step + lo);
      const std::size_t t01 = t00 + std::size_t(hi - lo), t10 = t00 + std::size_t(hi - lo) * size, t11 = t10 + (t01 - t00);
      if (!read[t00] || !read[t01] || !read[t10] || !read[t11]) continue;
      const Rgba8 a[4] = {image.pixels[t00], image.pixels[t01], image.pixels[t10], image.pixels[t11]};
      const Rgba8 b = model.color[m];
      stored[0] += 0.25 * (a[0].r + a[1].r + a[2].r + a[3].r);
      stored[1] += 0.25 * (a[0].g + a[1].g + a[2].g + a[3].g);
      stored[2] += 0.25 * (a[0].b + a[1].b + a[2].b + a[3].b);
      seen[0] += b.r, seen[1] += b.g, seen[2] += b.b;
      ++pixels;
    }
  if (pixels < kImageCheckMinPixels) return "";
  double worst = 0;
  for (int c = 0; c < 3; ++c) {
    stored[std::size_t(c)] /= pixels, seen[std::size_t(c)] /= pixels;
    worst = std::max(worst, std::fabs(stored[std::size_t(c)] - seen[std::size_t(c)]));
  }
  if (worst <= kImageCheckMaxMeanDifference) return "";
  return at + " image: mean colour " + rgb_text(stored) + " at " + std::to_string(pixels) +
         " pixels its mesh reads, the model shows " + rgb_text(seen) + " there";
}

}  // namespace

std::string check_face_images_against_model(const CellRow& row, const FarFieldResampler& resample) {
  for (const SampleRow& s : row.samples) {
    std::vector<std::pair<const FaceRow*, DecodedImage>> images;
    int size = 0;
    for (const FaceRow& f : s.faces)
      if (f.image_format != kNoFaceImage && f.triangles > 0 && f.face >= 0 && f.face < kCubeFaces) {
        images.emplace_back(&f, decode_image(f.image));
        size = std::max(size, images.back().second.width);
      }
    if (images.empty() || size < 1) continue;
    const CubeSample model = resample(row, s.eye, image_check_resample_size(size));
    for (const auto& [f, image] : images) {
      const std::string at = "sample " + std::to_string(s.index) + " face " + std::to_string(f->face);
      if (std::string problem = compare_face(*f, image, model.faces[std::size_t(f->face)], at); !problem.empty())
        return problem;
    }
  }
  return "";
}

}  // namespace cellbake
