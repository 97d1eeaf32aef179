// Halving an image as rows arrive, top row first, with memory of one row per
// level: the same texels as stages/texture_sampling.h halve_texels applied
// `levels` times to the whole image held bottom row first (per level: sides
// halved rounding down, never below 1; with an odd height the file's top row
// is the one dropped, as it is the last row bottom-up; with an odd width the
// rightmost column; each output texel the rounded mean of its 2x2, 2x1 or
// 1x2 box). Used by texture_import.cpp so a large texture is reduced to
// --max-texture-size while it is decoded strip by strip.
#pragma once

#include <cstdint>
#include <vector>

#include "stages/texture.h"

namespace cellbake {

class TextureRowReducer {
 public:
  // An image of `width` x `height` texels (>= 1 each), halved `levels` times.
  TextureRowReducer(int width, int height, int levels);

  // Takes the next row of the input (top first; `width` texels).
  void add_row(const Rgba8* row);

  int out_width() const { return out_width_; }
  int out_height() const { return out_height_; }

  // The reduced image, bottom row first (stages/texture.h), once every input
  // row has been added. Throws std::logic_error when rows are missing.
  std::vector<Rgba8> take_bottom_up();

 private:
  struct Level {
    int width = 0, height = 0;  // of this level's input
    int rows_seen = 0;
    bool pending = false;  // holding the first row of a pair
    std::vector<Rgba8> held;
  };
  void push(std::size_t level, const Rgba8* row);

  std::vector<Level> levels_;
  int out_width_ = 0, out_height_ = 0;
  std::vector<Rgba8> out_;  // top row first
  std::vector<Rgba8> scratch_;
};

}  // namespace cellbake
