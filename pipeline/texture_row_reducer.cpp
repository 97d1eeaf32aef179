#include "pipeline/texture_row_reducer.h"

#include <algorithm>
#include <stdexcept>

namespace cellbake {

TextureRowReducer::TextureRowReducer(int width, int height, int levels) {
  if (width < 1 || height < 1 || levels < 0) throw std::invalid_argument("TextureRowReducer: bad size");
  for (int i = 0; i < levels; ++i) {
    Level l;
    l.width = width, l.height = height;
    levels_.push_back(std::move(l));
    width = std::max(1, width / 2), height = std::max(1, height / 2);
  }
  out_width_ = width, out_height_ = height;
  out_.reserve(std::size_t(width) * std::size_t(height));
}

void TextureRowReducer::add_row(const Rgba8* row) { push(0, row); }

void TextureRowReducer::push(std::size_t index, const Rgba8* row) {
  if (index == levels_.size()) {
    out_.insert(out_.end(), row, row + out_width_);
    return;
  }
  Level& l = levels_[index];
  const int row_number = l.rows_seen++;
  const int w = std::max(1, l.width / 2), sx = l.width > 1 ? 2 : 1;
  std::vector<Rgba8> halved(static_cast<std::size_t>(w));
  const auto emit = [&](const Rgba8* a, const Rgba8* b) {  // b == nullptr: a single row (height 1)
    const int n = sx * (b ? 2 : 1);
    for (int x = 0; x < w; ++x) {
      int sum[4] = {0, 0, 0, 0};
      for (const Rgba8* r : {a, b}) {
        if (!r) continue;
        for (int dx = 0; dx < sx; ++dx) {
          const Rgba8& t = r[x * sx + dx];
          sum[0] += t.r, sum[1] += t.g, sum[2] += t.b, sum[3] += t.a;
        }
      }
      halved[std::size_t(x)] = {
          static_cast<std::uint8_t>((sum[0] + n / 2) / n), static_cast<std::uint8_t>((sum[1] + n / 2) / n),
          static_cast<std::uint8_t>((sum[2] + n / 2) / n), static_cast<std::uint8_t>((sum[3] + n / 2) / n)};
    }
    push(index + 1, halved.data());
  };
  if (l.height == 1) return emit(row, nullptr);
  if (l.height % 2 == 1 && row_number == 0) return;  // bottom up, the odd top row has no partner
  if (!l.pending) {
    l.held.assign(row, row + l.width);
    l.pending = true;
    return;
  }
  l.pending = false;
  // Bottom-up pairs are (lower row, upper row); the sum does not depend on the order.
  emit(l.held.data(), row);
}

std::vector<Rgba8> TextureRowReducer::take_bottom_up() {
  const std::size_t w = std::size_t(out_width_), h = std::size_t(out_height_);
  if (out_.size() != w * h) throw std::logic_error("TextureRowReducer: image rows missing");
  std::vector<Rgba8> flipped(out_.size());
  for (std::size_t y = 0; y < h; ++y)
    std::copy_n(out_.begin() + std::ptrdiff_t((h - 1 - y) * w), w, flipped.begin() + std::ptrdiff_t(y * w));
  out_.clear();
  out_.shrink_to_fit();
  return flipped;
}

}  // namespace cellbake
