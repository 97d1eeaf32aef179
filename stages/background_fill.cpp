// Push-pull fill of background texels (Gortler et al. 1996, "The Lumigraph",
// §3.3's pull-push interpolation), used so that bilinear texture sampling of a
// textured depth mesh (Wilson 2002 ch. 5) never blends in a black background.
#include "stages/background_fill.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "stages/texel_footprint.h"

namespace cellbake {
namespace {

struct Level {
  int size = 0;
  std::vector<float> rgb;     // premultiplied by weight
  std::vector<float> weight;  // 0..1 coverage
};

// Push-pull over `face.color`: pixels with keep[k] == 0 get the smooth
// extension of the kept ones, alpha 0.
void fill_unkept(CubeFace& face, const std::vector<std::uint8_t>& keep) {
  const int n = face.size;
  std::vector<Level> levels(1);
  Level& base = levels[0];
  base.size = n;
  base.rgb.assign(std::size_t(n) * n * 3, 0.f);
  base.weight.assign(std::size_t(n) * n, 0.f);
  bool any = false, all = true;
  for (std::size_t k = 0; k < face.depth.size(); ++k) {
    if (!keep[k]) {
      all = false;
      continue;
    }
    any = true;
    base.weight[k] = 1.f;
    base.rgb[3 * k] = face.color[k].r, base.rgb[3 * k + 1] = face.color[k].g, base.rgb[3 * k + 2] = face.color[k].b;
  }
  if (!any || all) return;
  // Pull: 2x2 box averages (odd sizes clamp), weights saturate at 1.
  while (levels.back().size > 1) {
    const Level& fine = levels.back();
    Level coarse;
    coarse.size = (fine.size + 1) / 2;
    coarse.rgb.assign(std::size_t(coarse.size) * coarse.size * 3, 0.f);
    coarse.weight.assign(std::size_t(coarse.size) * coarse.size, 0.f);
    for (int j = 0; j < coarse.size; ++j)
      for (int i = 0; i < coarse.size; ++i) {
        float w = 0, c[3] = {0, 0, 0};
        for (int dj = 0; dj < 2; ++dj)
          for (int di = 0; di < 2; ++di) {
            const int fi = std::min(2 * i + di, fine.size - 1), fj = std::min(2 * j + dj, fine.size - 1);
            const std::size_t k = std::size_t(fj) * fine.size + fi;
            w += fine.weight[k];
            for (int ch = 0; ch < 3; ++ch) c[ch] += fine.rgb[3 * k + ch];
          }
        const std::size_t k = std::size_t(j) * coarse.size + i;
        const float scale = w > 1.f ? 1.f / w : 1.f;  // keep premultiplied colours normalised to weight <= 1
        coarse.weight[k] = std::min(w, 1.f);
        for (int ch = 0; ch < 3; ++ch) coarse.rgb[3 * k + ch] = c[ch] * scale;
      }
    levels.push_back(std::move(coarse));
  }
  // Push: each level's missing weight is filled from the coarser level.
  for (int l = static_cast<int>(levels.size()) - 2; l >= 0; --l) {
    Level& fine = levels[static_cast<std::size_t>(l)];
    const Level& coarse = levels[static_cast<std::size_t>(l) + 1];
    for (int j = 0; j < fine.size; ++j)
      for (int i = 0; i < fine.size; ++i) {
        const std::size_t k = std::size_t(j) * fine.size + i, kc = std::size_t(j / 2) * coarse.size + i / 2;
        const float missing = 1.f - fine.weight[k];
        if (missing <= 0.f || coarse.weight[kc] <= 0.f) continue;
        const float cw = missing / coarse.weight[kc];
        for (int ch = 0; ch < 3; ++ch) fine.rgb[3 * k + ch] += coarse.rgb[3 * kc + ch] * cw;
        fine.weight[k] = 1.f;
      }
  }
  const Level& top = levels[0];
  const auto byte = [](float v) { return static_cast<std::uint8_t>(std::lround(std::fmin(255.f, std::fmax(0.f, v)))); };
  for (std::size_t k = 0; k < face.depth.size(); ++k) {
    if (keep[k] || top.weight[k] <= 0.f) continue;
    const float inv = 1.f / top.weight[k];
    face.color[k] = {byte(top.rgb[3 * k] * inv), byte(top.rgb[3 * k + 1] * inv), byte(top.rgb[3 * k + 2] * inv), 0};
  }
}

bool well_formed(const CubeFace& face) {
  const int n = face.size;
  return n > 0 && face.depth.size() == std::size_t(n) * n && face.color.size() == face.depth.size();
}

}  // namespace

void fill_background_colors(CubeFace& face) {
  if (!well_formed(face)) return;
  std::vector<std::uint8_t> keep(face.depth.size());
  for (std::size_t k = 0; k < keep.size(); ++k) keep[k] = std::isfinite(face.depth[k]) ? 1 : 0;
  fill_unkept(face, keep);
}

void fill_unread_colors(CubeFace& face, const FaceMesh& mesh) {
  if (!well_formed(face)) return;
  std::vector<std::uint8_t> keep = texels_read_by(mesh, face.size);
  for (std::size_t k = 0; k < keep.size(); ++k) keep[k] = keep[k] && std::isfinite(face.depth[k]) ? 1 : 0;
  fill_unkept(face, keep);
}

}  // namespace cellbake
