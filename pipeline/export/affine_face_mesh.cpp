#include "pipeline/export/affine_face_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace cellbake {
namespace {

Vec3d to_double(const Vec3f& p) { return {p.x, p.y, p.z}; }

void check(const FaceMesh& mesh, int face) {
  if (face < 0 || face >= kCubeFaces) throw std::invalid_argument("face mesh: face " + std::to_string(face) + " out of range");
  if (mesh.uvs.size() != mesh.positions.size())
    throw std::invalid_argument("face mesh: " + std::to_string(mesh.uvs.size()) + " texture coordinates for " +
                                std::to_string(mesh.positions.size()) + " positions");
  for (std::uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) throw std::invalid_argument("face mesh: index " + std::to_string(i) + " out of range");
}

}  // namespace

double affine_uv_edge_error_px(double qa, double qb, double pixel_length) {
  const double lo = std::min(qa, qb), hi = std::max(qa, qb);
  if (!(lo > 0)) return 0;
  const double root = std::sqrt(hi / lo);
  return pixel_length * (root - 1) / (root + 1);
}

void snap_to_sample_rays(FaceMesh& mesh, int face) {
  check(mesh, face);
  const FaceBasis b = cube_face_basis(face);
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const Vec3d p = to_double(mesh.positions[i]);
    const Uv& uv = mesh.uvs[i];
    const Vec3d on_ray = cube_face_direction(b, 2.0 * uv.u - 1.0, 1.0 - 2.0 * uv.v) * dot(p, b.forward);
    // Vertices already on their ray to float rounding keep their bits (shared borders stay identical).
    if (length(p - on_ray) > 1e-6 * length(p))
      mesh.positions[i] = {static_cast<float>(on_ray.x), static_cast<float>(on_ray.y), static_cast<float>(on_ray.z)};
  }
}

AffineRefinement refine_for_affine_uvs(const FaceMesh& mesh, int face, int width, int height, double tolerance_px) {
  check(mesh, face);
  if (width < 1 || height < 1) throw std::invalid_argument("face mesh: image size must be positive");
  if (!(tolerance_px > 0)) throw std::invalid_argument("face mesh: the texture tolerance must be positive");
  const Vec3d forward = cube_face_basis(face).forward;
  std::vector<Vec3d> positions;
  std::vector<Uv> uvs = mesh.uvs;
  std::vector<double> depth;
  positions.reserve(mesh.positions.size());
  for (const Vec3f& p : mesh.positions) {
    positions.push_back(to_double(p));
    depth.push_back(dot(positions.back(), forward));
  }
  const auto error_px = [&](std::uint32_t a, std::uint32_t b) {
    const double du = (uvs[a].u - uvs[b].u) * width, dv = (uvs[a].v - uvs[b].v) * height;
    return affine_uv_edge_error_px(depth[a], depth[b], std::sqrt(du * du + dv * dv));
  };

  AffineRefinement out;
  std::vector<std::uint32_t> indices = mesh.indices;
  // Each round halves the texture length of every edge it splits, so edges
  // reach the tolerance within log2(face diagonal / tolerance) rounds.
  for (int round = 0; round < 64; ++round) {
    std::unordered_map<std::uint64_t, std::uint32_t> middle;  // edge (lo << 32 | hi) -> new vertex
    const auto split = [&](std::uint32_t a, std::uint32_t b) -> std::int64_t {
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      if (auto it = middle.find(key); it != middle.end()) return it->second;
      if (!(depth[a] > 0 && depth[b] > 0) || error_px(a, b) <= tolerance_px) return -1;
      // The point of the edge whose projection is the texture midpoint:
      // parameter qa / (qa + qb) from a.
      const double t = depth[a] / (depth[a] + depth[b]);
      const auto m = static_cast<std::uint32_t>(positions.size());
      positions.push_back(positions[a] + (positions[b] - positions[a]) * t);
      uvs.push_back({(uvs[a].u + uvs[b].u) * 0.5f, (uvs[a].v + uvs[b].v) * 0.5f});
      depth.push_back(dot(positions.back(), forward));
      middle.emplace(key, m);
      return m;
    };
    std::vector<std::uint32_t> next;
    next.reserve(indices.size());
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
      const std::array<std::uint32_t, 3> v0{indices[t], indices[t + 1], indices[t + 2]};
      std::array<std::int64_t, 3> m0{};
      for (int e = 0; e < 3; ++e) m0[e] = split(v0[e], v0[(e + 1) % 3]);
      const int splits = int(m0[0] >= 0) + int(m0[1] >= 0) + int(m0[2] >= 0);
      // Rotate so that edge 0 is split (one split), or edge 2 is the unsplit one (two).
      int r = 0;
      if (splits == 1) r = m0[0] >= 0 ? 0 : (m0[1] >= 0 ? 1 : 2);
      if (splits == 2) r = m0[2] < 0 ? 0 : (m0[0] < 0 ? 1 : 2);
      std::array<std::uint32_t, 3> v;
      std::array<std::int64_t, 3> m;
      for (int k = 0; k < 3; ++k) v[k] = v0[(k + r) % 3], m[k] = m0[(k + r) % 3];
      const auto tri = [&next](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        next.insert(next.end(), {a, b, c});
      };
      const auto mid = [&m](int k) { return static_cast<std::uint32_t>(m[k]); };
      switch (splits) {
        case 0: tri(v[0], v[1], v[2]); break;
        case 1:
          tri(v[0], mid(0), v[2]);
          tri(mid(0), v[1], v[2]);
          break;
        case 2:
          tri(mid(0), v[1], mid(1));
          tri(v[0], mid(0), mid(1));
          tri(v[0], mid(1), v[2]);
          break;
        default:
          tri(v[0], mid(0), mid(2));
          tri(mid(0), v[1], mid(1));
          tri(mid(2), mid(1), v[2]);
          tri(mid(0), mid(1), mid(2));
      }
    }
    out.edges_split += middle.size();
    indices = std::move(next);
    if (middle.empty()) break;
  }
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3)
    for (int e = 0; e < 3; ++e)
      if (depth[indices[t + e]] > 0 && depth[indices[t + (e + 1) % 3]] > 0)
        out.max_edge_error_px = std::max(out.max_edge_error_px, error_px(indices[t + e], indices[t + (e + 1) % 3]));
  out.mesh.indices = std::move(indices);
  out.mesh.uvs = std::move(uvs);
  out.mesh.positions.reserve(positions.size());
  for (const Vec3d& p : positions)
    out.mesh.positions.push_back({static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
  return out;
}

}  // namespace cellbake
