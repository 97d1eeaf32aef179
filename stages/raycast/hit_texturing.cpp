#include "stages/raycast/hit_texturing.h"

#include <algorithm>
#include <cmath>

namespace cellbake {

std::shared_ptr<const TextureMips> MipTextureCache::get(std::int64_t id, const ChunkSource& source) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (auto it = entries_.find(id); it != entries_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.recency);
      return it->second.mips;
    }
  }
  // Decode outside the lock; two threads may both decode the same texture once.
  auto mips = std::make_shared<const TextureMips>(*source.load_texture(id));
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = entries_.find(id); it != entries_.end()) return it->second.mips;
  lru_.push_front(id);
  entries_[id] = {mips, lru_.begin()};
  bytes_ += mips->bytes();
  while (bytes_ > cap_bytes_ && lru_.size() > 1) {
    auto victim = entries_.find(lru_.back());
    bytes_ -= victim->second.mips->bytes();
    entries_.erase(victim);
    lru_.pop_back();
  }
  return mips;
}

std::size_t MipTextureCache::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

HitTexturer::HitTexturer(const ChunkSource& source, MipTextureCache& cache)
    : source_(source), cache_(cache), materials_(source.materials()) {
  for (const Material& m : materials_) untextured_ &= m.texture_id <= 0;
}

HitTexel HitTexturer::texel(const SurfaceHit& hit, const Vec3f& dir, float t, const Vec3f& step_x,
                            const Vec3f& step_y) const {
  HitTexel out;
  const Chunk& c = *hit.chunk;
  if (c.uvs.empty()) return out;
  const std::uint32_t index = c.materials.empty() ? 0 : c.materials[hit.triangle];
  if (index >= materials_.size() || materials_[index].texture_id <= 0) return out;
  const Material& material = materials_[index];
  auto& mips = in_use_[material.texture_id];
  if (!mips) mips = cache_.get(material.texture_id, source_);

  const std::size_t i = 3 * std::size_t(hit.triangle);
  const std::uint32_t a = c.indices[i], b = c.indices[i + 1], d = c.indices[i + 2];
  const float w0 = 1.0f - hit.u - hit.v, w1 = hit.u, w2 = hit.v;
  const Uv &ua = c.uvs[a], &ub = c.uvs[b], &ud = c.uvs[d];
  const float u = w0 * ua.u + w1 * ub.u + w2 * ud.u, v = w0 * ua.v + w1 * ub.v + w2 * ud.v;

  // Ray differentials: the surface displacement of a one-pixel step, in the
  // triangle's edge basis, mapped to texels.
  const Vec3f &pa = c.positions[a], &pb = c.positions[b], &pd = c.positions[d];
  const Vec3d e1{pb.x - pa.x, pb.y - pa.y, pb.z - pa.z}, e2{pd.x - pa.x, pd.y - pa.y, pd.z - pa.z};
  const Vec3d n = cross(e1, e2), ray{dir.x, dir.y, dir.z};
  const double g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2), det = g11 * g22 - g12 * g12;
  const double n_dot_ray = dot(n, ray);
  double footprint = 0;
  if (det > 0 && std::abs(n_dot_ray) > 1e-12 * length(n) * length(ray)) {
    const double du1 = (ub.u - ua.u) * mips->width(0), dv1 = (ub.v - ua.v) * mips->height(0);
    const double du2 = (ud.u - ua.u) * mips->width(0), dv2 = (ud.v - ua.v) * mips->height(0);
    for (const Vec3f& step : {step_x, step_y}) {
      const Vec3d shift = Vec3d{step.x, step.y, step.z} * double(t);
      const Vec3d on_plane = shift - ray * (dot(n, shift) / n_dot_ray);
      const double r1 = dot(e1, on_plane), r2 = dot(e2, on_plane);
      const double alpha = (g22 * r1 - g12 * r2) / det, beta = (g11 * r2 - g12 * r1) / det;
      const double du = alpha * du1 + beta * du2, dv = alpha * dv1 + beta * dv2;
      footprint = std::max(footprint, std::sqrt(du * du + dv * dv));
    }
  } else {
    footprint = 1e30;  // seen edge-on: the coarsest level, as GL's derivatives would give
  }
  out.textured = true;
  out.texel = mips->sample(u, v, static_cast<float>(std::min(footprint, 1e30)));
  out.dropped = material.alpha_test && out.texel[3] < 0.5f;
  return out;
}

}  // namespace cellbake
