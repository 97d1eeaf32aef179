// Image metrics on hand-built frames with analytic answers: identical frames,
// a known uniform colour error, a known hole mask, known skins and depth errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "viewer/image_metrics.h"

namespace cellbake {
namespace {

constexpr float kSky = std::numeric_limits<float>::infinity();

// A w x h frame with colour `c` and depth `d` everywhere.
ViewFrame flat(int w, int h, Rgba8 c, float d) {
  ViewFrame f;
  f.width = w, f.height = h;
  f.color.assign(static_cast<std::size_t>(w) * h, c);
  f.depth.assign(static_cast<std::size_t>(w) * h, d);
  return f;
}

// A frame with a vertical stripe pattern, so SSIM sees structure.
ViewFrame stripes(int w, int h, int phase) {
  ViewFrame f = flat(w, h, {}, 5.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::uint8_t v = ((x + phase) / 2) % 2 ? 220 : 30;
      f.color[static_cast<std::size_t>(y) * w + x] = {v, v, v, 255};
    }
  return f;
}

TEST(ImageMetrics, IdenticalFramesHaveInfinitePsnrAndNoError) {
  const ViewFrame a = stripes(32, 24, 0);
  const ImageMetrics m = compare_frames(a, a);
  EXPECT_TRUE(std::isinf(m.psnr_db));
  EXPECT_DOUBLE_EQ(m.ssim, 1.0);
  EXPECT_EQ(m.hole_fraction, 0.0);
  EXPECT_EQ(m.skin_fraction, 0.0);
  EXPECT_EQ(m.depth_error_median, 0.0);
  EXPECT_EQ(m.extra_fraction, 0.0);
  EXPECT_EQ(m.truth_covered_pixels, 32u * 24u);
}

TEST(ImageMetrics, UniformColourOffsetGivesKnownPsnr) {
  // Every covered pixel off by 10 in each channel: MSE = 100.
  const ViewFrame truth = flat(16, 16, {100, 100, 100, 255}, 2.0f);
  const ViewFrame impostor = flat(16, 16, {110, 110, 110, 255}, 2.0f);
  const ImageMetrics m = compare_frames(impostor, truth);
  EXPECT_NEAR(m.psnr_db, 10 * std::log10(255.0 * 255.0 / 100.0), 1e-9);
  // Constant images: SSIM reduces to the luminance term (2 ab + C1) / (a^2 + b^2 + C1).
  const double c1 = 2.55 * 2.55;
  EXPECT_NEAR(m.ssim, (2 * 100.0 * 110.0 + c1) / (100.0 * 100.0 + 110.0 * 110.0 + c1), 1e-9);
}

TEST(ImageMetrics, OnlyCoveredPixelsCountTowardsPsnr) {
  // Half the image is sky in both (ignored); the other half differs by 30 in red only: MSE = 900 / 3.
  ViewFrame truth = flat(8, 8, {50, 50, 50, 255}, 3.0f);
  ViewFrame impostor = truth;
  for (std::size_t i = 0; i < 32; ++i) truth.depth[i] = impostor.depth[i] = kSky;
  for (std::size_t i = 32; i < 64; ++i) impostor.color[i].r = 80;
  const ImageMetrics m = compare_frames(impostor, truth);
  EXPECT_NEAR(m.psnr_db, 10 * std::log10(255.0 * 255.0 / 300.0), 1e-9);
}

TEST(ImageMetrics, ShiftedStripesLowerSsim) {
  const ViewFrame a = stripes(32, 32, 0), b = stripes(32, 32, 2);  // stripes inverted
  const ImageMetrics m = compare_frames(b, a);
  EXPECT_LT(m.ssim, 0.0);  // anti-correlated structure
  EXPECT_GT(compare_frames(stripes(32, 32, 1), a).ssim, m.ssim);
}

TEST(ImageMetrics, MaskedSsimOfAFullMaskIsCompareFramesSsim) {
  const ViewFrame a = stripes(32, 24, 0), b = stripes(32, 24, 1);
  const std::vector<std::uint8_t> all(a.color.size(), 1);
  EXPECT_DOUBLE_EQ(masked_ssim(b.color, a.color, 32, 24, all), compare_frames(b, a).ssim);
}

TEST(ImageMetrics, MaskedSsimIgnoresWindowsTouchingUnmaskedPixels) {
  // Identical on the left 16 columns, inverted stripes on the right: with the
  // left half as mask, every counted window is identical (SSIM exactly 1).
  const ViewFrame truth = stripes(32, 32, 0);
  ViewFrame impostor = stripes(32, 32, 2);
  std::vector<std::uint8_t> left(truth.color.size(), 0);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 16; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * 32 + x;
      impostor.color[i] = truth.color[i];
      left[i] = 1;
    }
  EXPECT_LT(compare_frames(impostor, truth).ssim, 0.5);
  EXPECT_NEAR(masked_ssim(impostor.color, truth.color, 32, 32, left), 1.0, 1e-12);
  // Constant images masked to their top half: the luminance term, as unmasked.
  const ViewFrame dark = flat(16, 16, {100, 100, 100, 255}, 2.0f), light = flat(16, 16, {110, 110, 110, 255}, 2.0f);
  std::vector<std::uint8_t> top(256, 0);
  std::fill(top.begin(), top.begin() + 128, std::uint8_t{1});
  const double c1 = 2.55 * 2.55;
  EXPECT_NEAR(masked_ssim(light.color, dark.color, 16, 16, top),
              (2 * 100.0 * 110.0 + c1) / (100.0 * 100.0 + 110.0 * 110.0 + c1), 1e-9);
}

TEST(ImageMetrics, MaskedSsimIsNanWithoutAWholeWindowAndRejectsBadSizes) {
  const ViewFrame a = stripes(8, 8, 0);
  std::vector<std::uint8_t> mask(64, 1);
  mask[27] = 0;  // the only 8x8 window now touches an unmasked pixel
  EXPECT_TRUE(std::isnan(masked_ssim(a.color, a.color, 8, 8, mask)));
  mask[27] = 1;
  EXPECT_DOUBLE_EQ(masked_ssim(a.color, a.color, 8, 8, mask), 1.0);
  mask.pop_back();
  EXPECT_THROW(masked_ssim(a.color, a.color, 8, 8, mask), std::invalid_argument);
  EXPECT_THROW(masked_ssim(a.color, a.color, 0, 8, std::vector<std::uint8_t>{}), std::invalid_argument);
}

TEST(ImageMetrics, KnownHoleMaskGivesExactHoleFraction) {
  // Truth covers 60 of 100 pixels; the impostor misses 15 of those and covers 4 sky pixels.
  ViewFrame truth = flat(10, 10, {90, 90, 90, 255}, 4.0f);
  for (std::size_t i = 60; i < 100; ++i) truth.depth[i] = kSky;
  ViewFrame impostor = truth;
  for (std::size_t i = 0; i < 15; ++i) impostor.depth[i * 4] = kSky;  // 0, 4, ..., 56: all truth-covered
  for (std::size_t i = 60; i < 64; ++i) impostor.depth[i] = 4.0f;
  const ImageMetrics m = compare_frames(impostor, truth);
  EXPECT_EQ(m.truth_covered_pixels, 60u);
  EXPECT_DOUBLE_EQ(m.hole_fraction, 15.0 / 60.0);
  EXPECT_DOUBLE_EQ(m.extra_fraction, 4.0 / 40.0);
  EXPECT_EQ(m.skin_fraction, 0.0);
}

TEST(ImageMetrics, SkinsAreNearerSurfacesBeyondTheThreshold) {
  // Truth at depth 10 everywhere. Impostor: 10 pixels at 9 (10 % nearer: skin),
  // 10 at 9.6 (4 % nearer: not a skin), 10 at 12 (farther: never a skin), rest exact.
  ViewFrame truth = flat(10, 10, {90, 90, 90, 255}, 10.0f);
  ViewFrame impostor = truth;
  for (std::size_t i = 0; i < 10; ++i) impostor.depth[i] = 9.0f;
  for (std::size_t i = 10; i < 20; ++i) impostor.depth[i] = 9.6f;
  for (std::size_t i = 20; i < 30; ++i) impostor.depth[i] = 12.0f;
  const ImageMetrics m = compare_frames(impostor, truth);
  EXPECT_DOUBLE_EQ(m.skin_fraction, 0.1);
  EXPECT_EQ(m.hole_fraction, 0.0);
  // Relative errors: 10 x 0.1, 10 x 0.04, 10 x 0.2, 70 x 0: median 0.
  EXPECT_EQ(m.depth_error_median, 0.0);
  ImageMetricsParams strict;
  strict.skin_relative_depth = 0.03;
  EXPECT_DOUBLE_EQ(compare_frames(impostor, truth, strict).skin_fraction, 0.2);
}

TEST(ImageMetrics, DepthErrorMedianOfEvenCountAveragesTheMiddle) {
  ViewFrame truth = flat(2, 2, {90, 90, 90, 255}, 10.0f);
  ViewFrame impostor = truth;
  impostor.depth = {10.0f, 11.0f, 12.0f, 14.0f};  // relative errors 0, 0.1, 0.2, 0.4
  EXPECT_NEAR(compare_frames(impostor, truth).depth_error_median, 0.15, 1e-6);
}

TEST(ImageMetrics, ErrorImageMarksHolesSkinsAndExtras) {
  ViewFrame truth = flat(4, 1, {90, 90, 90, 255}, 10.0f);
  truth.depth[3] = kSky;
  ViewFrame impostor = truth;
  impostor.depth[0] = kSky;  // hole
  impostor.depth[1] = 5.0f;  // skin
  impostor.depth[3] = 7.0f;  // extra surface
  const std::vector<Rgba8> e = error_image(impostor, truth);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[0], (Rgba8{255, 0, 255, 255}));
  EXPECT_EQ(e[1], (Rgba8{255, 255, 0, 255}));
  EXPECT_EQ(e[2], (Rgba8{0, 0, 64, 255}));  // exact match: the ramp's start
  EXPECT_EQ(e[3], (Rgba8{0, 255, 255, 255}));
}

TEST(ImageMetrics, BlankFramesAreOneColourOrEmpty) {
  // Nothing covered: blank.
  EXPECT_TRUE(is_blank(flat(8, 8, {0, 0, 0, 0}, kSky)));
  // One colour over every covered pixel (a black model): blank, whatever the background.
  ViewFrame black = flat(8, 8, {0, 0, 0, 255}, 3.0f);
  black.depth[5] = kSky;
  black.color[5] = {90, 90, 90, 0};
  EXPECT_TRUE(is_blank(black));
  // Alpha alone does not make a picture.
  black.color[6].a = 17;
  EXPECT_TRUE(is_blank(black));
  // Two colours among the covered pixels: not blank.
  black.color[7] = {0, 0, 1, 255};
  EXPECT_FALSE(is_blank(black));
  EXPECT_FALSE(is_blank(stripes(16, 16, 0)));
  ViewFrame bad = flat(4, 4, {}, 1.0f);
  bad.depth.pop_back();
  EXPECT_THROW(is_blank(bad), std::invalid_argument);
}

TEST(ImageMetrics, BoxDownsampleAveragesColourAndKeepsTheNearestDepth) {
  ViewFrame f = flat(4, 2, {0, 0, 0, 0}, kSky);
  // Left 2x2 block: one covered pixel of 200 at depth 5, one of 100 at depth 3.
  f.color[0] = {200, 200, 200, 255}, f.depth[0] = 5.0f;
  f.color[5] = {100, 0, 0, 255}, f.depth[5] = 3.0f;
  const ViewFrame d = box_downsample(f, 2);
  ASSERT_EQ(d.width, 2);
  ASSERT_EQ(d.height, 1);
  EXPECT_EQ(d.color[0].r, 75);  // (200 + 100 + 0 + 0) / 4
  EXPECT_EQ(d.color[0].g, 50);
  EXPECT_FLOAT_EQ(d.depth[0], 3.0f);
  EXPECT_FALSE(d.covered(1));  // nothing covered in the right block
  // A sub-pixel stripe is measured by its coverage: the same stripe one
  // pixel over differs pixel for pixel, but not once filtered.
  const ViewFrame a = stripes(8, 8, 0), b = stripes(8, 8, 1);
  EXPECT_LT(compare_frames(a, b).psnr_db, compare_frames(box_downsample(a, 2), box_downsample(b, 2)).psnr_db);
  EXPECT_EQ(box_downsample(f, 1).color.size(), f.color.size());
  EXPECT_THROW(box_downsample(f, 0), std::invalid_argument);
  EXPECT_THROW(box_downsample(f, 3), std::invalid_argument);  // taller than the frame
}

TEST(ImageMetrics, MismatchedFramesAreRejected) {
  const ViewFrame a = flat(4, 4, {}, 1.0f), b = flat(4, 5, {}, 1.0f);
  EXPECT_THROW(compare_frames(a, b), std::invalid_argument);
  ViewFrame broken = a;
  broken.depth.pop_back();
  EXPECT_THROW(compare_frames(broken, a), std::invalid_argument);
  EXPECT_THROW(error_image(a, b), std::invalid_argument);
}

}  // namespace
}  // namespace cellbake
