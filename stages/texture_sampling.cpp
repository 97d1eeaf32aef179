#include "stages/texture_sampling.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cellbake {
namespace {

// The texel index `i` wrapped into [0, size) (GL §8.14.2, wrap modes).
int wrap_index(int i, int size, TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::clamp:
      return std::clamp(i, 0, size - 1);
    case TextureWrap::mirror: {
      const int period = 2 * size;
      int m = i % period;
      if (m < 0) m += period;
      return m < size ? m : period - 1 - m;
    }
    default: {
      int m = i % size;
      return m < 0 ? m + size : m;
    }
  }
}

}  // namespace

std::vector<Rgba8> halve_texels(const std::vector<Rgba8>& texels, int& width, int& height) {
  const int w = std::max(1, width / 2), h = std::max(1, height / 2);
  const int sx = width > 1 ? 2 : 1, sy = height > 1 ? 2 : 1;
  std::vector<Rgba8> out(std::size_t(w) * std::size_t(h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int sum[4] = {0, 0, 0, 0};
      for (int dy = 0; dy < sy; ++dy)
        for (int dx = 0; dx < sx; ++dx) {
          const Rgba8& t = texels[std::size_t(y * sy + dy) * std::size_t(width) + std::size_t(x * sx + dx)];
          sum[0] += t.r, sum[1] += t.g, sum[2] += t.b, sum[3] += t.a;
        }
      const int n = sx * sy;
      out[std::size_t(y) * std::size_t(w) + std::size_t(x)] = {
          static_cast<std::uint8_t>((sum[0] + n / 2) / n), static_cast<std::uint8_t>((sum[1] + n / 2) / n),
          static_cast<std::uint8_t>((sum[2] + n / 2) / n), static_cast<std::uint8_t>((sum[3] + n / 2) / n)};
    }
  width = w;
  height = h;
  return out;
}

TextureMips::TextureMips(const TextureImage& image) : wrap_u_(image.wrap_u), wrap_v_(image.wrap_v) {
  if (image.width <= 0 || image.height <= 0 ||
      image.texels.size() != std::size_t(image.width) * std::size_t(image.height))
    throw std::invalid_argument("texture " + std::to_string(image.id) + ": texels do not match its size");
  levels_.push_back({image.width, image.height, image.texels});
  while (levels_.back().width > 1 || levels_.back().height > 1) {
    Level next{levels_.back().width, levels_.back().height, {}};
    next.texels = halve_texels(levels_.back().texels, next.width, next.height);
    levels_.push_back(std::move(next));
  }
  for (const Level& l : levels_) bytes_ += l.texels.size() * sizeof(Rgba8);
}

Rgbaf TextureMips::sample_level(float u, float v, int level) const {
  const Level& l = levels_[static_cast<std::size_t>(std::clamp(level, 0, levels() - 1))];
  if (!std::isfinite(u) || !std::isfinite(v)) u = v = 0;
  // Texel centres sit at half-integers: i0 = floor(u * w - 0.5), weight = fraction.
  const double x = double(u) * l.width - 0.5, y = double(v) * l.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const float ax = static_cast<float>(x - fx), ay = static_cast<float>(y - fy);
  const auto clamp_index = [](double i) { return static_cast<int>(std::clamp(i, -1e9, 1e9)); };
  const int x0 = clamp_index(fx), y0 = clamp_index(fy);
  const int xs[2] = {wrap_index(x0, l.width, wrap_u_), wrap_index(x0 + 1, l.width, wrap_u_)};
  const int ys[2] = {wrap_index(y0, l.height, wrap_v_), wrap_index(y0 + 1, l.height, wrap_v_)};
  Rgbaf out{0, 0, 0, 0};
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const float w = (i ? ax : 1 - ax) * (j ? ay : 1 - ay);
      const Rgba8& t = l.texels[std::size_t(ys[j]) * std::size_t(l.width) + std::size_t(xs[i])];
      out[0] += w * t.r, out[1] += w * t.g, out[2] += w * t.b, out[3] += w * t.a;
    }
  for (float& c : out) c /= 255.f;
  return out;
}

Rgbaf TextureMips::sample(float u, float v, float footprint) const {
  const float lambda = footprint > 1 && std::isfinite(footprint) ? std::log2(footprint) : 0.f;
  if (lambda <= 0) return sample_level(u, v, 0);
  const float top = static_cast<float>(levels() - 1);
  const float d = std::min(lambda, top);
  const int lo = static_cast<int>(std::floor(d));
  const float f = d - static_cast<float>(lo);
  const Rgbaf a = sample_level(u, v, lo);
  if (f == 0 || lo + 1 > levels() - 1) return a;
  const Rgbaf b = sample_level(u, v, lo + 1);
  Rgbaf out;
  for (int k = 0; k < 4; ++k) out[k] = a[k] + f * (b[k] - a[k]);
  return out;
}

}  // namespace cellbake
