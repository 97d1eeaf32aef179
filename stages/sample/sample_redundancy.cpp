// Redundant-point removal for incremental textured depth meshes, Wilson 2002
// §5.2.1 ("each delta scan contains only those surfaces not present in any scan
// on which it depends") and Appendix A (unlike the pseudocode there, the root
// is tested like every other ancestor and the loop is bounded).
#include "stages/sample/sample_redundancy.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace cellbake {
namespace {

struct Projection {
  int face = 0;
  double x = 0, y = 0;  // continuous pixel coordinates: pixel (i, j) centre is (i, j)
  double depth = 0;     // planar depth along the face's forward axis
};

// The cube face and pixel position of direction v (relative to the eye).
Projection project(const Vec3d& v, int size) {
  const double ax = std::abs(v.x), ay = std::abs(v.y), az = std::abs(v.z);
  int face;
  if (ax >= ay && ax >= az) face = v.x >= 0 ? 0 : 1;
  else if (ay >= az) face = v.y >= 0 ? 2 : 3;
  else face = v.z >= 0 ? 4 : 5;
  const FaceBasis b = cube_face_basis(face);
  Projection p;
  p.face = face;
  p.depth = dot(v, b.forward);
  const double s = dot(v, b.right) / p.depth, t = dot(v, b.up) / p.depth;
  p.x = (s + 1) * 0.5 * size - 0.5;
  p.y = (1 - t) * 0.5 * size - 0.5;
  return p;
}

double inverse_at(const CubeFace& f, int i, int j) {
  const float d = f.depth[static_cast<std::size_t>(j) * f.size + i];
  return std::isfinite(d) ? 1.0 / d : 0.0;  // 0 = background
}

// Turns kept (1) components of fewer than `min_size` pixels that touch no
// background (0) pixel into redundant (2).
void drop_specks(std::vector<std::uint8_t>& state, int n, int min_size) {
  std::vector<int> stack, members;
  std::vector<std::uint8_t> seen(state.size(), 0);
  for (std::size_t start = 0; start < state.size(); ++start) {
    if (state[start] != 1 || seen[start]) continue;
    stack.assign(1, int(start));
    members.clear();
    seen[start] = 1;
    bool touches_background = false;
    while (!stack.empty()) {
      const int k = stack.back();
      stack.pop_back();
      members.push_back(k);
      const int i = k % n, j = k / n;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int ii = i + di, jj = j + dj;
          if ((di == 0 && dj == 0) || ii < 0 || jj < 0 || ii >= n || jj >= n) continue;
          const int q = jj * n + ii;
          if (state[q] == 0) touches_background = true;
          if (state[q] == 1 && !seen[q]) {
            seen[q] = 1;
            stack.push_back(q);
          }
        }
    }
    if (!touches_background && int(members.size()) < min_size)
      for (int k : members) state[std::size_t(k)] = 2;
  }
}

}  // namespace

bool sample_holds_point(const CubeSample& a, const Vec3d& point, const RedundancyParams& prm) {
  const int n = a.faces[0].size;
  const Projection p = project(point - a.eye, n);
  if (!(p.depth > 0)) return false;
  const CubeFace& f = a.faces[static_cast<std::size_t>(p.face)];
  const double x = std::clamp(p.x, 0.0, n - 1.0), y = std::clamp(p.y, 0.0, n - 1.0);
  const int i0 = std::min(static_cast<int>(x), std::max(0, n - 2)), j0 = std::min(static_cast<int>(y), std::max(0, n - 2));
  const int i1 = std::min(i0 + 1, n - 1), j1 = std::min(j0 + 1, n - 1);
  const double fx = x - i0, fy = y - j0;
  const double w = 1.0 / p.depth;
  const double w00 = inverse_at(f, i0, j0), w10 = inverse_at(f, i1, j0), w01 = inverse_at(f, i0, j1),
               w11 = inverse_at(f, i1, j1);
  const double lo = std::min({w00, w10, w01, w11}), hi = std::max({w00, w10, w01, w11});
  if (lo > 0 && hi <= lo * (1 + prm.jump)) {
    // One surface: bilinear in inverse depth (exact on a plane), with an error
    // allowance from the local second differences where the neighbours exist.
    const double interpolated = (w00 * (1 - fx) + w10 * fx) * (1 - fy) + (w01 * (1 - fx) + w11 * fx) * fy;
    // The allowance only grows with each second difference: stop as soon as
    // it covers the miss (the same answer as taking every one first). Each
    // pixel around the 2x2 is read once (n >= 2 here whenever one exists:
    // then i1 = i0 + 1 and j1 = j0 + 1).
    const double miss = std::abs(interpolated - w), base = prm.tolerance * w;
    double curvature = std::abs(w00 + w11 - w10 - w01);
    if (miss <= base + 0.5 * curvature) return true;
    const auto second = [&](double a0, double b0, double c0) {
      if (a0 <= 0 || c0 <= 0 || std::max(a0, c0) > std::min(a0, c0) * (1 + prm.jump)) return false;
      curvature = std::max(curvature, std::abs(a0 - 2 * b0 + c0));
      return miss <= base + 0.5 * curvature;
    };
    if (i0 >= 1 &&
        (second(inverse_at(f, i0 - 1, j0), w00, w10) || second(inverse_at(f, i0 - 1, j1), w01, w11)))
      return true;
    if (i1 + 1 < n &&
        (second(w00, w10, inverse_at(f, i1 + 1, j0)) || second(w01, w11, inverse_at(f, i1 + 1, j1))))
      return true;
    if (j0 >= 1 &&
        (second(inverse_at(f, i0, j0 - 1), w00, w01) || second(inverse_at(f, i1, j0 - 1), w10, w11)))
      return true;
    if (j1 + 1 < n &&
        (second(w00, w01, inverse_at(f, i0, j1 + 1)) || second(w10, w11, inverse_at(f, i1, j1 + 1))))
      return true;
    return false;
  }
  // Across a depth jump: extrapolate each neighbour's own surface to the
  // point, along each axis from its same-surface neighbour ahead (towards the
  // point) when there is one; from the one behind, or flat when the pixel has
  // none along that axis (a feature one pixel thin, or the last pixel before a
  // silhouette), with an allowance of `unknown_slope` per pixel of offset.
  const int ni[4] = {i0, i1, i0, i1}, nj[4] = {j0, j0, j1, j1};
  const double nw[4] = {w00, w10, w01, w11};
  for (int k = 0; k < 4; ++k) {
    if (nw[k] <= 0) continue;
    const auto same = [&](int i, int j) {
      if (i < 0 || j < 0 || i >= n || j >= n) return 0.0;
      const double v = inverse_at(f, i, j);
      return v > 0 && std::max(v, nw[k]) <= std::min(v, nw[k]) * (1 + prm.jump) ? v : 0.0;
    };
    double predicted = nw[k], allowance = prm.tolerance * w;
    const auto extrapolate = [&](double offset, int di, int dj) {
      const double ahead = offset >= 0 ? same(ni[k] + di, nj[k] + dj) : same(ni[k] - di, nj[k] - dj);
      const double behind = offset >= 0 ? same(ni[k] - di, nj[k] - dj) : same(ni[k] + di, nj[k] + dj);
      const double step = std::abs(offset);
      if (ahead > 0) {
        predicted += (ahead - nw[k]) * step;
        allowance += prm.edge_tolerance * std::abs(ahead - nw[k]) * step;
      } else {
        if (behind > 0) predicted += (nw[k] - behind) * step;
        allowance += prm.unknown_slope * w * step;
      }
    };
    extrapolate(x - ni[k], 1, 0);
    extrapolate(y - nj[k], 0, 1);
    if (std::abs(predicted - w) <= allowance) return true;
  }
  return false;
}

RedundancyStats remove_redundant_pixels(CubeSample& delta, std::span<const CubeSample* const> ancestors,
                                        const RedundancyParams& prm) {
  const int n = delta.faces[0].size;
  for (const CubeFace& f : delta.faces)
    if (f.size != n || f.depth.size() != std::size_t(n) * n || f.color.size() != f.depth.size())
      throw std::invalid_argument("redundancy: delta sample faces differ in size");
  for (const CubeSample* a : ancestors)
    for (const CubeFace& f : a->faces)
      if (f.size != n || f.depth.size() != std::size_t(n) * n)
        throw std::invalid_argument("redundancy: ancestor faces differ from the delta sample's size " +
                                    std::to_string(n));
  if (!(prm.tolerance >= 0) || !(prm.jump > 0) || !(prm.edge_tolerance >= 0) || prm.keep_margin < 0 || !(prm.unknown_slope >= 0))
    throw std::invalid_argument("redundancy: bad parameters");
  RedundancyStats stats;
  if (ancestors.empty()) {
    for (const CubeFace& f : delta.faces)
      for (float d : f.depth) stats.covered += std::isfinite(d) ? 1 : 0;
    return stats;
  }
  std::vector<std::uint8_t> state;  // 0 background, 1 kept, 2 redundant
  // Per pixel: whether a kept pixel lies in its row, at it or one either side.
  std::vector<std::uint8_t> across(std::size_t(n) * n);
  for (int face = 0; face < kCubeFaces; ++face) {
    CubeFace& f = delta.faces[static_cast<std::size_t>(face)];
    const FaceBasis b = cube_face_basis(face);
    state.assign(f.depth.size(), 0);
    for (int j = 0; j < n; ++j) {
      const double t = 1 - 2 * (j + 0.5) / n;
      for (int i = 0; i < n; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * n + i;
        const float d = f.depth[k];
        if (!std::isfinite(d)) continue;
        ++stats.covered;
        const double s = 2 * (i + 0.5) / n - 1;
        const Vec3d point = delta.eye + cube_face_direction(b, s, t) * static_cast<double>(d);
        bool held = false;
        for (const CubeSample* a : ancestors)
          if ((held = sample_holds_point(*a, point, prm))) break;
        state[k] = held ? 2 : 1;
      }
    }
    // Drop kept specks smaller than min_island pixels (8-connected) that touch
    // no background: noise of the test, not disocclusions worth a mesh.
    if (prm.min_island > 1) drop_specks(state, n, prm.min_island);
    // Grow the kept pixels back over removed ones by keep_margin rings: a
    // removed pixel with a kept one among its 8 neighbours is kept (the 3x3
    // dilation of the kept pixels, done as a row pass and a column pass).
    for (int ring = 0; ring < prm.keep_margin; ++ring) {
      for (int j = 0; j < n; ++j) {
        const std::uint8_t* row = state.data() + static_cast<std::size_t>(j) * n;
        std::uint8_t* out = across.data() + static_cast<std::size_t>(j) * n;
        for (int i = 0; i < n; ++i)
          out[i] = (row[i] == 1) | (i > 0 && row[i - 1] == 1) | (i + 1 < n && row[i + 1] == 1);
      }
      for (int j = 0; j < n; ++j) {
        std::uint8_t* row = state.data() + static_cast<std::size_t>(j) * n;
        const std::uint8_t* mid = across.data() + static_cast<std::size_t>(j) * n;
        const std::uint8_t* up = j > 0 ? mid - n : nullptr;
        const std::uint8_t* down = j + 1 < n ? mid + n : nullptr;
        for (int i = 0; i < n; ++i) {
          const bool near_kept = mid[i] | (up && up[i]) | (down && down[i]);
          if (row[i] == 2 && near_kept) row[i] = 1;
        }
      }
    }
    for (std::size_t k = 0; k < state.size(); ++k)
      if (state[k] == 2) {
        f.depth[k] = kBackgroundDepth;
        f.color[k] = Rgba8{0, 0, 0, 0};
        ++stats.removed;
      }
  }
  return stats;
}

}  // namespace cellbake
