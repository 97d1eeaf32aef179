// CPU texture filtering with the rules of OpenGL's GL_LINEAR_MIPMAP_LINEAR
// (OpenGL 4.6 core specification, §8.14 "Texture minification", §8.14.2 "Mipmapping"),
// so a ray caster samples a material's texture as the GL renderers do: a mip
// chain where each level halves the previous one (floor, at least 1) with a
// box filter, bilinear filtering inside a level at texel centres (u * size -
// 0.5), linear blending between the two levels around the level of detail
// lambda = log2(footprint in base-level texels), and the wrap modes repeat,
// clamp-to-edge and mirrored repeat.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "stages/texture.h"

namespace cellbake {

// An RGBA colour with components in [0, 1].
using Rgbaf = std::array<float, 4>;

// The next mip level of a width x height image (texels row by row): each side
// halved (floor, at least 1) and each texel the rounded mean of the 2 x 2 (or
// 2 x 1, 1 x 2) block it covers, as glGenerateMipmap's box filter; an odd
// last row or column is dropped. Sets `width` and `height` to the new size.
std::vector<Rgba8> halve_texels(const std::vector<Rgba8>& texels, int& width, int& height);

class TextureMips {
 public:
  // Builds every level down to 1 x 1 from `image` (its texels, bottom row
  // first). Throws std::invalid_argument when its texels do not match its size.
  explicit TextureMips(const TextureImage& image);

  // The filtered colour at texture coordinates (u, v) (origin bottom-left) for
  // a pixel whose footprint spans `footprint` base-level texels (the larger
  // of the screen-space derivative lengths of (u * width, v * height));
  // footprints <= 1 magnify from the base level.
  Rgbaf sample(float u, float v, float footprint) const;
  // Bilinear lookup in level `level` (clamped to the chain).
  Rgbaf sample_level(float u, float v, int level) const;

  int levels() const { return static_cast<int>(levels_.size()); }
  int width(int level) const { return levels_[static_cast<std::size_t>(level)].width; }
  int height(int level) const { return levels_[static_cast<std::size_t>(level)].height; }
  // Bytes of all levels.
  std::size_t bytes() const { return bytes_; }

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<Rgba8> texels;
  };
  std::vector<Level> levels_;
  TextureWrap wrap_u_, wrap_v_;
  std::size_t bytes_ = 0;
};

}  // namespace cellbake
