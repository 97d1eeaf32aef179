// Decoded texture images as the renderers use them: RGBA8 texels of the base
// level (mip levels are built by whoever samples them) and the wrap modes the
// source file asked for.
//
// Conventions: texture coordinates have their origin at the image's
// bottom-left corner (OBJ, OpenGL; assimp converts glTF's top-left origin on
// import), and `texels` is stored bottom row first, so texel (x, y) covers
// u in [x / width, (x + 1) / width), v in [y / height, (y + 1) / height).
#pragma once

#include <cstdint>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

enum class TextureWrap : std::uint8_t { repeat = 0, clamp = 1, mirror = 2 };

struct TextureImage {
  std::int64_t id = 0;
  int width = 0, height = 0;
  std::vector<Rgba8> texels;  // width * height, bottom row first
  TextureWrap wrap_u = TextureWrap::repeat, wrap_v = TextureWrap::repeat;
  bool has_alpha = false;  // some texel has alpha < 255
  std::size_t bytes() const { return texels.size() * sizeof(Rgba8); }
};

}  // namespace cellbake
