#include "stages/model_analysis/up_axis_from_geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cellbake {
namespace {

std::string score_text(const std::array<double, 3>& s) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "plane score z %.3f, y %.3f, x %.3f", s[2], s[1], s[0]);
  return buf;
}

std::string facing_text(const std::array<double, 3>& f, int best) {
  const int other = best == 2 ? 1 : 2;
  const char* names = "xyz";
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.0f %% of the area within 45 degrees of %c, %c %.0f %%, x %.0f %%", 100 * f[best],
                names[best], names[other], 100 * f[other], 100 * f[0]);
  return buf;
}

}  // namespace

UpAxisEvidence::UpAxisEvidence(const Box3d& bounds, const UpAxisParams& params)
    : params_(params), bounds_(bounds) {
  if (bounds.empty() || params.bins < 1) return;
  double longest = 0;
  for (int a = 0; a < 3; ++a) longest = std::max(longest, bounds.hi[a] - bounds.lo[a]);
  if (!(longest > 0) || !std::isfinite(longest)) return;
  bin_size_ = longest / params.bins;
  for (int a = 0; a < 3; ++a)
    area_[a].assign(std::size_t((bounds.hi[a] - bounds.lo[a]) / bin_size_) + 1, 0.0);
}

void UpAxisEvidence::add_triangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
  const Vec3d n = cross(p1 - p0, p2 - p0);
  const double len = length(n);
  if (!(len > 0) || !std::isfinite(len)) return;
  const double area = 0.5 * len;
  total_area_ += area;
  for (int a = 0; a < 3; ++a)
    if (std::abs(n[a]) >= params_.facing_cos * len) facing_area_[a] += area;
  if (bin_size_ == 0) return;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(n[a]) < params_.plane_cos * len) continue;
    const double at = ((p0[a] + p1[a] + p2[a]) / 3 - bounds_.lo[a]) / bin_size_;
    const std::size_t last = area_[a].size() - 1;
    area_[a][at <= 0 ? 0 : std::min(last, std::size_t(at))] += area;
  }
}

void UpAxisEvidence::add_chunk(const Chunk& chunk) {
  for (std::size_t t = 0; t + 2 < chunk.indices.size(); t += 3)
    add_triangle(chunk.world(chunk.indices[t]), chunk.world(chunk.indices[t + 1]),
                 chunk.world(chunk.indices[t + 2]));
}

UpAxisGuess UpAxisEvidence::guess() const {
  UpAxisGuess g;
  if (!(total_area_ > 0) || bin_size_ == 0) {
    g.evidence = "no surface area to measure";
    return g;
  }
  for (int a = 0; a < 3; ++a) {
    const std::vector<double>& h = area_[a];
    double sum = 0;
    for (std::size_t i = 0; i < h.size(); ++i) {
      if (h[i] == 0) continue;
      const double around = h[i] + (i > 0 ? h[i - 1] : 0) + (i + 1 < h.size() ? h[i + 1] : 0);
      sum += h[i] * around;
    }
    g.score[a] = sum / (total_area_ * total_area_);
    g.facing[a] = facing_area_[a] / total_area_;
  }
  const int best = g.score[2] >= g.score[1] ? 2 : 1;  // ties go to z, the default
  const double other = std::max(g.score[0], g.score[best == 2 ? 1 : 2]);
  g.ratio = other > 0 ? g.score[best] / other : (g.score[best] > 0 ? INFINITY : 0);
  const std::string scores = score_text(g.score);
  if (g.score[0] > g.score[1] && g.score[0] > g.score[2] && g.score[0] >= params_.min_score &&
      g.score[0] >= params_.min_ratio * std::max(g.score[1], g.score[2])) {
    g.evidence = "large flat surfaces face x, which cannot be baked as up (" + scores + ")";
    return g;
  }
  if (g.score[best] >= params_.min_score && g.ratio >= params_.min_ratio) {
    g.axis = best == 2 ? "z" : "y";
    g.evidence = "large flat surfaces face " + g.axis + " (" + scores + ")";
    return g;
  }
  // The planes do not say: terrain, whose area mostly faces up without being flat?
  const int up = g.facing[2] >= g.facing[1] ? 2 : 1;
  const double rival = std::max(g.facing[0], g.facing[up == 2 ? 1 : 2]);
  if (g.facing[up] >= params_.min_facing_fraction && g.facing[up] >= params_.min_ratio * rival) {
    g.axis = up == 2 ? "z" : "y";
    g.from_facing = true;
    g.ratio = rival > 0 ? g.facing[up] / rival : INFINITY;
    g.evidence = "most of the surface faces " + g.axis + " though little of it is flat, as terrain does (" +
                 facing_text(g.facing, up) + "; " + scores + ")";
  } else if (g.score[best] < params_.min_score) {
    g.evidence = "too few large flat surfaces to tell (" + scores + ")";
  } else {
    g.evidence = "no axis stands out (" + scores + ")";
  }
  return g;
}

UpAxisGuess up_axis_from_geometry(const ChunkSource& source, const UpAxisParams& params) {
  const Box3d bounds = source.model_bounds();
  UpAxisEvidence evidence(bounds, params);
  if (!bounds.empty())
    for (const ChunkRef& ref : source.query(bounds)) evidence.add_chunk(*source.load(ref.id));
  return evidence.guess();
}

}  // namespace cellbake
