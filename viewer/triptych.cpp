#include "viewer/triptych.h"

#include <stdexcept>
#include <string>

namespace cellbake {

int triptych_width(int panel_width, int gap) { return 3 * panel_width + 2 * gap; }

std::vector<Rgba8> triptych(const ViewFrame& truth, const ViewFrame& impostor, const std::vector<Rgba8>& diff,
                            int gap, Rgba8 gap_color) {
  const int w = truth.width, h = truth.height;
  const std::size_t n = std::size_t(w) * std::size_t(h);
  if (gap < 0) throw std::invalid_argument("triptych: negative gap");
  if (impostor.width != w || impostor.height != h || truth.color.size() != n || impostor.color.size() != n ||
      diff.size() != n)
    throw std::invalid_argument("triptych: truth, impostor and difference differ in size (truth " +
                                std::to_string(w) + "x" + std::to_string(h) + ")");
  const int tw = triptych_width(w, gap);
  std::vector<Rgba8> out(std::size_t(tw) * std::size_t(h), gap_color);
  const std::vector<Rgba8>* panels[3] = {&truth.color, &impostor.color, &diff};
  for (int p = 0; p < 3; ++p)
    for (int y = 0; y < h; ++y) {
      const Rgba8* src = panels[p]->data() + std::size_t(y) * w;
      std::copy(src, src + w, out.begin() + std::ptrdiff_t(std::size_t(y) * tw + std::size_t(p) * (w + gap)));
    }
  return out;
}

std::vector<unsigned char> rgb24(const std::vector<Rgba8>& pixels) {
  std::vector<unsigned char> out(pixels.size() * 3);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    out[3 * i] = pixels[i].r;
    out[3 * i + 1] = pixels[i].g;
    out[3 * i + 2] = pixels[i].b;
  }
  return out;
}

}  // namespace cellbake
