// The colour-codec benches' input and error measure: the cube faces of each
// selected cell's centre sample (one sample per cell, as `cellbake bake` takes
// with samples.max=1, samples.initial=centre), background texels filled by
// push-pull as run_encode does before encoding, and the squared error /
// PSNR / SSIM of a decoded face against the uncompressed one over covered
// pixels only (finite depth: the pixels the depth meshes texture).
// Used by bench_image_codecs and bench_spatial_video. Header-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"
#include "pipeline/sample_backend.h"
#include "stages/background_fill.h"
#include "stages/encode/encode.h"
#include "storage/geometry_store.h"
#include "viewer/image_metrics.h"

namespace cellbake {

struct SampledFace {
  CellSpec cell;
  int face = 0;                      // cube face direction, 0..5
  int size = 0;                      // pixels per side
  std::vector<Rgba8> color;          // background filled
  std::vector<std::uint8_t> covered; // 1 where the depth is finite
  std::size_t covered_count = 0;
};

// The faces with at least one covered pixel of each cell in `cells`, in that
// order (cell, then face 0..5). Sets `config`'s sampling to one centre sample.
inline std::vector<SampledFace> sample_centre_faces(BakeConfig& config, const std::vector<CellSpec>& cells) {
  config.samples_initial = "centre";  // one sample per cell: whole faces, no delta scans
  config.samples_max = 1;
  GeometryStore store(config.store);
  const std::unique_ptr<CubeSampler> sampler =
      CubeSamplerFactory(parse_sample_backend(config.sample_backend), std::size_t(config.embree_cache_mb) << 20).make();
  std::vector<SampledFace> faces;
  for (const CellSpec& cell : cells) {
    CellWork work;
    work.cell = cell;
    run_cull_box(work, config, store);
    run_sample(work, config, store, *sampler);
    if (work.samples.empty()) continue;
    for (int d = 0; d < kCubeFaces; ++d) {
      CubeFace& f = work.samples[0].cube.faces[std::size_t(d)];
      SampledFace face;
      face.cell = cell;
      face.face = d;
      face.size = f.size;
      face.covered.resize(f.depth.size());
      for (std::size_t i = 0; i < f.depth.size(); ++i) {
        face.covered[i] = std::isfinite(f.depth[i]) ? 1 : 0;
        face.covered_count += face.covered[i];
      }
      if (face.covered_count == 0) continue;
      fill_background_colors(f);
      face.color = f.color;
      faces.push_back(std::move(face));
    }
  }
  if (faces.empty()) throw std::runtime_error("no face with covered pixels in the selected cells");
  return faces;
}

// Sum of squared R, G, B differences over the covered pixels (3 samples each).
inline double covered_sq_error(const SampledFace& f, const std::vector<Rgba8>& decoded) {
  if (decoded.size() != f.color.size()) throw std::runtime_error("decoded face has the wrong size");
  double se = 0;
  for (std::size_t i = 0; i < f.color.size(); ++i) {
    if (!f.covered[i]) continue;
    const Rgba8 &a = f.color[i], &b = decoded[i];
    const double dr = a.r - b.r, dg = a.g - b.g, db = a.b - b.b;
    se += dr * dr + dg * dg + db * db;
  }
  return se;
}

inline double psnr(double sq_error, double samples) {
  return sq_error <= 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 * samples / sq_error);
}

// SSIM over the face's covered pixels (viewer/image_metrics masked_ssim:
// 8x8 windows wholly on covered pixels); NaN when there is no such window.
inline double covered_ssim(const SampledFace& f, const std::vector<Rgba8>& decoded) {
  return masked_ssim(decoded, f.color, f.size, f.size, f.covered);
}

}  // namespace cellbake
