// Impostor-versus-truth image metrics (see image_metrics.h for definitions).
// SSIM: Wang, Bovik, Sheikh, Simoncelli, "Image quality assessment: from error
// visibility to structural similarity", IEEE TIP 13(4), 2004 — here with
// uniform 8x8 windows on luminance, computed with summed-area tables.
#include "viewer/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

void validate(const ViewFrame& f, const char* name) {
  if (f.width < 1 || f.height < 1)
    throw std::invalid_argument(std::string("image_metrics: ") + name + " frame has size " + std::to_string(f.width) +
                                "x" + std::to_string(f.height));
  const std::size_t n = static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height);
  if (f.color.size() != n || f.depth.size() != n)
    throw std::invalid_argument(std::string("image_metrics: ") + name + " frame does not hold width * height pixels");
}

void validate_pair(const ViewFrame& a, const ViewFrame& b) {
  validate(a, "impostor");
  validate(b, "truth");
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("image_metrics: frames differ in size (" + std::to_string(a.width) + "x" +
                                std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                                std::to_string(b.height) + ")");
}

bool is_skin(float d_impostor, float d_truth, double threshold) {
  return (static_cast<double>(d_truth) - d_impostor) / d_truth > threshold;
}

double luminance(Rgba8 c) { return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b; }

// Summed-area table with a zero first row and column: (w + 1) x (h + 1).
struct SummedArea {
  int w, h;
  std::vector<double> s;
  SummedArea(int width, int height) : w(width), h(height), s(static_cast<std::size_t>(width + 1) * (height + 1), 0.0) {}
  double& at(int x, int y) { return s[static_cast<std::size_t>(y) * (w + 1) + x]; }
  double sum(int x0, int y0, int x1, int y1) const {  // [x0, x1) x [y0, y1)
    const auto v = [&](int x, int y) { return s[static_cast<std::size_t>(y) * (w + 1) + x]; };
    return v(x1, y1) - v(x0, y1) - v(x1, y0) + v(x0, y0);
  }
};

// Sum and count of the SSIM of every 8x8 window (one window when the image
// is smaller) of two w x h images; with `mask`, only the windows whose pixels
// all have mask != 0.
struct SsimSum {
  double total = 0;
  long long windows = 0;
};
SsimSum sum_window_ssim(const std::vector<Rgba8>& a, const std::vector<Rgba8>& b, int w, int h,
                        const std::vector<std::uint8_t>* mask) {
  SummedArea sa(w, h), sb(w, h), saa(w, h), sbb(w, h), sab(w, h), sm(mask ? w : 0, mask ? h : 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const double ya = luminance(a[i]), yb = luminance(b[i]);
      const auto accumulate = [&](SummedArea& t, double v) {
        t.at(x + 1, y + 1) = v + t.at(x, y + 1) + t.at(x + 1, y) - t.at(x, y);
      };
      accumulate(sa, ya);
      accumulate(sb, yb);
      accumulate(saa, ya * ya);
      accumulate(sbb, yb * yb);
      accumulate(sab, ya * yb);
      if (mask) accumulate(sm, (*mask)[i] ? 1.0 : 0.0);
    }
  const int wx = std::min(8, w), wy = std::min(8, h);
  const double n = static_cast<double>(wx) * wy;
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  SsimSum s;
  for (int y = 0; y + wy <= h; ++y)
    for (int x = 0; x + wx <= w; ++x) {
      if (mask && sm.sum(x, y, x + wx, y + wy) < n) continue;  // integer counts: exact in doubles
      const double ma = sa.sum(x, y, x + wx, y + wy) / n, mb = sb.sum(x, y, x + wx, y + wy) / n;
      const double va = std::max(0.0, saa.sum(x, y, x + wx, y + wy) / n - ma * ma);
      const double vb = std::max(0.0, sbb.sum(x, y, x + wx, y + wy) / n - mb * mb);
      const double cov = sab.sum(x, y, x + wx, y + wy) / n - ma * mb;
      s.total += ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
      ++s.windows;
    }
  return s;
}

double mean_ssim(const ViewFrame& a, const ViewFrame& b) {
  const SsimSum s = sum_window_ssim(a.color, b.color, a.width, a.height, nullptr);
  return s.total / static_cast<double>(s.windows);
}

double median(std::vector<double>& v) {
  if (v.empty()) return 0;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

Rgba8 ramp(double e) {
  const auto lerp = [](double a, double b, double t) { return static_cast<std::uint8_t>(std::lround(a + (b - a) * t)); };
  if (e <= 0.25) {
    const double t = e / 0.25;
    return {0, lerp(0, 255, t), lerp(64, 0, t), 255};
  }
  const double t = std::min(1.0, (e - 0.25) / 0.25);
  return {lerp(0, 255, t), lerp(255, 0, t), 0, 255};
}

}  // namespace

bool ViewFrame::covered(std::size_t i) const { return std::isfinite(depth[i]); }

ViewFrame box_downsample(const ViewFrame& frame, int factor) {
  validate(frame, "supersampled");
  if (factor < 1 || frame.width < factor || frame.height < factor)
    throw std::invalid_argument("image_metrics: cannot box-filter a " + std::to_string(frame.width) + "x" +
                                std::to_string(frame.height) + " frame down by " + std::to_string(factor));
  if (factor == 1) return frame;
  ViewFrame out;
  out.width = frame.width / factor;
  out.height = frame.height / factor;
  out.color.resize(std::size_t(out.width) * std::size_t(out.height));
  out.depth.resize(out.color.size());
  const unsigned n = unsigned(factor * factor);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      unsigned sum[4] = {0, 0, 0, 0};
      float nearest = std::numeric_limits<float>::infinity();
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx) {
          const std::size_t i = std::size_t(y * factor + dy) * std::size_t(frame.width) + std::size_t(x * factor + dx);
          const Rgba8 c = frame.color[i];
          sum[0] += c.r, sum[1] += c.g, sum[2] += c.b, sum[3] += c.a;
          if (frame.covered(i)) nearest = std::min(nearest, frame.depth[i]);
        }
      const std::size_t o = std::size_t(y) * std::size_t(out.width) + std::size_t(x);
      out.color[o] = Rgba8{std::uint8_t((sum[0] + n / 2) / n), std::uint8_t((sum[1] + n / 2) / n),
                           std::uint8_t((sum[2] + n / 2) / n), std::uint8_t((sum[3] + n / 2) / n)};
      out.depth[o] = nearest;
    }
  return out;
}

ImageMetrics compare_frames(const ViewFrame& impostor, const ViewFrame& truth, const ImageMetricsParams& params) {
  validate_pair(impostor, truth);
  const std::size_t n = truth.color.size();
  ImageMetrics m;
  double squared_error = 0;
  std::uint64_t either = 0, truth_covered = 0, holes = 0, skins = 0, sky = 0, extra = 0;
  std::vector<double> depth_errors;
  for (std::size_t i = 0; i < n; ++i) {
    const bool ci = impostor.covered(i), ct = truth.covered(i);
    if (ci || ct) {
      ++either;
      const Rgba8 a = ci ? impostor.color[i] : Rgba8{0, 0, 0, 0};
      const Rgba8 b = ct ? truth.color[i] : Rgba8{0, 0, 0, 0};
      const double dr = double(a.r) - b.r, dg = double(a.g) - b.g, db = double(a.b) - b.b;
      squared_error += dr * dr + dg * dg + db * db;
    }
    if (!ct) {
      ++sky;
      if (ci) ++extra;
      continue;
    }
    ++truth_covered;
    if (!ci) {
      ++holes;
      continue;
    }
    if (is_skin(impostor.depth[i], truth.depth[i], params.skin_relative_depth)) ++skins;
    depth_errors.push_back(std::abs(static_cast<double>(impostor.depth[i]) - truth.depth[i]) / truth.depth[i]);
  }
  const double mse = either ? squared_error / (3.0 * static_cast<double>(either)) : 0.0;
  m.psnr_db = mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : std::numeric_limits<double>::infinity();
  m.ssim = mean_ssim(impostor, truth);
  m.truth_covered_pixels = truth_covered;
  m.hole_fraction = truth_covered ? static_cast<double>(holes) / static_cast<double>(truth_covered) : 0.0;
  m.skin_fraction = truth_covered ? static_cast<double>(skins) / static_cast<double>(truth_covered) : 0.0;
  m.extra_fraction = sky ? static_cast<double>(extra) / static_cast<double>(sky) : 0.0;
  m.depth_error_median = median(depth_errors);
  return m;
}

double masked_ssim(const std::vector<Rgba8>& a, const std::vector<Rgba8>& b, int width, int height,
                   const std::vector<std::uint8_t>& mask) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("masked_ssim: size " + std::to_string(width) + "x" + std::to_string(height));
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (a.size() != n || b.size() != n || mask.size() != n)
    throw std::invalid_argument("masked_ssim: an image or the mask does not hold width * height values");
  const SsimSum s = sum_window_ssim(a, b, width, height, &mask);
  return s.windows ? s.total / static_cast<double>(s.windows) : std::numeric_limits<double>::quiet_NaN();
}

bool is_blank(const ViewFrame& frame) {
  validate(frame, "blank test");
  const Rgba8* first = nullptr;
  for (std::size_t i = 0; i < frame.color.size(); ++i) {
    if (!frame.covered(i)) continue;
    const Rgba8& c = frame.color[i];
    if (!first) {
      first = &c;
    } else if (c.r != first->r || c.g != first->g || c.b != first->b) {
      return false;
    }
  }
  return true;
}

std::vector<Rgba8> error_image(const ViewFrame& impostor, const ViewFrame& truth, const ImageMetricsParams& params) {
  validate_pair(impostor, truth);
  std::vector<Rgba8> out(truth.color.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const bool ci = impostor.covered(i), ct = truth.covered(i);
    if (!ci && !ct) {
      out[i] = {0, 0, 0, 255};
    } else if (!ci) {
      out[i] = {255, 0, 255, 255};
    } else if (!ct) {
      out[i] = {0, 255, 255, 255};
    } else if (is_skin(impostor.depth[i], truth.depth[i], params.skin_relative_depth)) {
      out[i] = {255, 255, 0, 255};
    } else {
      const Rgba8 a = impostor.color[i], b = truth.color[i];
      const int e = std::max({std::abs(int(a.r) - b.r), std::abs(int(a.g) - b.g), std::abs(int(a.b) - b.b)});
      out[i] = ramp(e / 255.0);
    }
  }
  return out;
}

}  // namespace cellbake
