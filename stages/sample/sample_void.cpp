// Void-surface objective for Voronoi best-next-view sampling (Wilson 2002,
// ch. 3, §3.4.2: the solid angle subtended by the void surface at a
// candidate). The thesis builds each sample's void surface from its skin
// triangles and marks a pixel of a panorama rendered at the candidate as void
// when every sample's void surface is visible there (a stencil count; the
// Appendix A pseudocode has the stencil arguments swapped). Here the same idea
// is carried out by space carving, without triangles: a view ray sees the
// global void surface when it leaves the union of the samples' free space
// (the visible volume, §3.1.2) other than through a sampled surface. Each
// ray is marched against the samples' depth cube maps, and the void rays'
// pixels are summed by their solid angles in closed form (equal to the
// spherical-polygon area of equation (19)). See sample_void.h for the
// contract.
#include "stages/sample/sample_void.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cellbake {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Face f's basis as coordinate axes: forward = fwd_sign * e[fwd_axis], etc.
struct FaceAxes {
  int fwd_axis = 0, right_axis = 0, up_axis = 0;
  double fwd_sign = 0, right_sign = 0, up_sign = 0;
};

void axis_of(const Vec3d& v, int& axis, double& sign) {
  for (int a = 0; a < 3; ++a)
    if (v[a] != 0) {
      axis = a;
      sign = v[a] > 0 ? 1 : -1;
    }
}

std::array<FaceAxes, kCubeFaces> face_axes() {
  std::array<FaceAxes, kCubeFaces> out;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis b = cube_face_basis(f);
    axis_of(b.forward, out[f].fwd_axis, out[f].fwd_sign);
    axis_of(b.right, out[f].right_axis, out[f].right_sign);
    axis_of(b.up, out[f].up_axis, out[f].up_sign);
  }
  return out;
}

// The face a direction falls on: dominant axis, ties to x then y.
int face_of(const double v[3], double& z) {
  const double ax = std::fabs(v[0]), ay = std::fabs(v[1]), az = std::fabs(v[2]);
  if (ax >= ay && ax >= az) {
    z = ax;
    return v[0] >= 0 ? 0 : 1;
  }
  if (ay >= az) {
    z = ay;
    return v[1] >= 0 ? 2 : 3;
  }
  z = az;
  return v[2] >= 0 ? 4 : 5;
}

enum class RayVerdict : std::uint8_t { void_surface, seen };

struct PreparedSample {
  Vec3d eye;
  int n = 0;
  double half_n = 0;
  std::array<const float*, kCubeFaces> depth{};
};

// Where a point falls in one sample: planar depth z and the stored depth.
struct Projection {
  double z = 0, depth = kInf;
  bool certified = true;
};

// The candidate's neighbourhood as one sample sees it: every point of the ball
// of `radius` around the candidate is certified free by the sample and off its
// surfaces (free), or uncertified and off its surfaces (blocked), so marching
// can skip the sample while t < radius. radius 0: not known.
struct NearBall {
  double radius = 0;
  bool free = false;
};

class Marcher {
 public:
  Marcher(const Vec3d& candidate, std::span<const VoidSample> samples, const VoidParams& params,
          double max_distance)
      : candidate_(candidate), params_(params), max_distance_(max_distance), axes_(face_axes()) {
    prepared_.reserve(samples.size());
    for (const VoidSample& s : samples) {
      PreparedSample p;
      p.eye = s.cube->eye;
      p.n = s.cube->faces[0].size;
      p.half_n = 0.5 * p.n;
      for (int f = 0; f < kCubeFaces; ++f) p.depth[f] = s.cube->faces[f].depth.data();
      prepared_.push_back(p);
    }
    // Skip, on every ray, the steps inside the balls where no sample can change its verdict.
    double common = kInf;
    bool any_free = false;
    near_.resize(prepared_.size());
    for (std::size_t k = 0; k < prepared_.size(); ++k) {
      near_[k] = near_ball(prepared_[k], max_distance);
      common = std::min(common, near_[k].radius);
      any_free = any_free || near_[k].free;
    }
    if (common > 0 && !any_free) all_void_ = true;  // every sample blocked at the first step
    // The marching distances are the same on every ray: find the first one
    // outside every ball (and the one before it).
    first_t_ = params.start_distance;
    while (first_t_ < common && first_t_ < max_distance) {
      before_first_t_ = first_t_;
      first_t_ = next_t(first_t_);
    }
    prev_certified_.resize(samples.size());
    prev_depth_.resize(samples.size());
    tried_background_.resize(samples.size());
  }

  // How the ray from the candidate along unit `dir` ends: void or seen.
  RayVerdict march(const Vec3d& dir) {
    if (all_void_) return RayVerdict::void_surface;
    const double tol = params_.surface_tolerance;
    const double jump = params_.jump;
    const double unknown = std::numeric_limits<double>::quiet_NaN();
    const bool skipped = before_first_t_ > 0;  // the steps before first_t_ lie in every ball
    for (std::size_t k = 0; k < prepared_.size(); ++k) {
      prev_certified_[k] = skipped && near_[k].free;
      prev_depth_[k] = unknown;
      tried_background_[k] = 0;
    }
    Vec3d prev_x = candidate_ + dir * before_first_t_;
    for (double t = first_t_;; t = next_t(t)) {
      const Vec3d x = candidate_ + dir * t;
      bool any_certified = false, all_background = true;
      int untried_background = -1;
      for (std::size_t k = 0; k < prepared_.size(); ++k) {
        if (t < near_[k].radius) {
          prev_certified_[k] = near_[k].free;
          prev_depth_[k] = unknown;
          any_certified = any_certified || near_[k].free;
          continue;
        }
        const Projection p = project(prepared_[k], x);
        if (p.depth < kInf) {
          all_background = false;
          if (std::fabs(p.z - p.depth) <= tol * p.z) return RayVerdict::seen;  // on a sampled surface
          if (!p.certified && prev_certified_[k]) {
            const double before =
                std::isnan(prev_depth_[k]) ? project(prepared_[k], prev_x).depth : prev_depth_[k];
            if (std::fabs(p.depth - before) <= jump * std::min(p.depth, before))
              return RayVerdict::seen;  // through a surface
          }
        } else if (!tried_background_[k] && untried_background < 0) {
          untried_background = static_cast<int>(k);
        }
        prev_certified_[k] = p.certified;
        prev_depth_[k] = p.depth;
        any_certified = any_certified || p.certified;
      }
      if (!any_certified) return RayVerdict::void_surface;
      if (t >= max_distance_) return RayVerdict::seen;
      // Every sample sees background here: if one of them sees only
      // background along the rest of the ray, it certifies all of it.
      if (all_background && untried_background >= 0) {
        tried_background_[untried_background] = 1;
        if (rest_is_background(prepared_[untried_background], x, dir)) return RayVerdict::seen;
      }
      prev_x = x;
    }
  }

 private:
  double next_t(double t) const { return std::min(t * (1 + params_.step_ratio), max_distance_); }

  Projection project(const PreparedSample& s, const Vec3d& x) const {
    const double v[3] = {x.x - s.eye.x, x.y - s.eye.y, x.z - s.eye.z};
    Projection p;
    const int face = face_of(v, p.z);
    if (!(p.z > 0)) return p;  // at the eye: free
    const FaceAxes& a = axes_[face];
    const double scale = s.half_n / p.z;
    const double fi = s.half_n + a.right_sign * v[a.right_axis] * scale;
    const double fj = s.half_n - a.up_sign * v[a.up_axis] * scale;
    const int i = std::clamp(static_cast<int>(fi), 0, s.n - 1);
    const int j = std::clamp(static_cast<int>(fj), 0, s.n - 1);
    p.depth = s.depth[face][static_cast<std::size_t>(j) * s.n + i];
    p.certified = p.z < p.depth;
    return p;
  }

  // The largest ball around the candidate (radius |candidate - eye| / 4,
  // halved until it works or stops being useful) that sample s sees as wholly
  // free or wholly blocked, judged from the depth range over the pixels the
  // ball can project to. Planar depths of ball points lie in
  // |c|_inf -+ radius (c = candidate - eye).
  NearBall near_ball(const PreparedSample& s, double max_distance) const {
    const Vec3d c = candidate_ - s.eye;
    const double c_inf = std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)});
    const double tol = params_.surface_tolerance;
    for (double r = std::min(0.25 * length(c), max_distance); r >= 2 * params_.start_distance; r *= 0.5) {
      const double free_below = (c_inf + r) * (1 + tol), blocked_above = (c_inf - r) * (1 - tol);
      float lo = 0, hi = 0;
      footprint_depth_range(s, c, r, free_below, blocked_above, lo, hi);
      if (free_below < lo) return {r, true};
      if (hi < blocked_above) return {r, false};
    }
    return {};
  }

  // The smallest and largest stored depth over a set of pixels of s that
  // holds every pixel a point of the ball (centre c relative to the eye,
  // radius r < |c|) projects to: per face, the ball's (s, t) bounds, from
  // its tangent planes through the eye when it lies wholly in front of the
  // face, else from interval bounds on the ball's points inside the face's
  // frustum (forward component >= (|c| - r) / sqrt(3) there), plus one pixel.
  // Stops early, with a partial range, once lo <= free_below and hi >= blocked_above.
  void footprint_depth_range(const PreparedSample& s, const Vec3d& c, double r, double free_below,
                             double blocked_above, float& lo, float& hi) const {
    lo = kBackgroundDepth;
    hi = 0;
    const double min_forward = (length(c) - r) / std::sqrt(3.0);
    for (int f = 0; f < kCubeFaces; ++f) {
      const FaceAxes& a = axes_[f];
      const double fc = a.fwd_sign * c[a.fwd_axis];
      if (fc + r < min_forward) continue;  // no ball point in this face's frustum
      // Bounds of (o . v) / (f . v) over the ball, o = right or up.
      auto range = [&](double oc, double& from, double& to) {
        if (fc > r) {
          const double root = r * std::sqrt(fc * fc + oc * oc - r * r), den = fc * fc - r * r;
          from = (oc * fc - root) / den;
          to = (oc * fc + root) / den;
        } else {
          const double d0 = std::max(min_forward, fc - r), d1 = fc + r;
          from = std::min((oc - r) / d0, (oc - r) / d1);
          to = std::max((oc + r) / d0, (oc + r) / d1);
        }
      };
      double s0, s1, t0, t1;
      range(a.right_sign * c[a.right_axis], s0, s1);
      range(a.up_sign * c[a.up_axis], t0, t1);
      if (s0 > 1 || s1 < -1 || t0 > 1 || t1 < -1) continue;
      auto pixel = [&](double p) {
        return static_cast<int>(
            std::clamp(std::floor(s.half_n * (1 + std::clamp(p, -1.0, 1.0))), 0.0, s.n - 1.0));
      };
      const int i0 = std::max(pixel(s0) - 1, 0), i1 = std::min(pixel(s1) + 1, s.n - 1);
      const int j0 = std::max(pixel(-t1) - 1, 0), j1 = std::min(pixel(-t0) + 1, s.n - 1);
      const float* depth = s.depth[f];
      for (int j = j0; j <= j1; ++j) {
        const float* row = depth + static_cast<std::size_t>(j) * s.n;
        for (int i = i0; i <= i1; ++i) {
          lo = std::min(lo, row[i]);
          hi = std::max(hi, row[i]);
        }
        if (lo <= free_below && hi >= blocked_above) return;
      }
    }
  }

  // True when every pixel of sample s that project() can give for a point
  // x + u dir (u >= 0) is background, so s certifies every such point. Per
  // face, the ray clipped to the face's frustum (widened by a hair, as
  // face_of's choice at a frustum edge may round either way) projects to a
  // segment in pixel coordinates, walked cell by cell (Amanatides & Woo
  // 1987) together with the neighbour cells whose border the segment passes
  // within kWalkMargin pixels of (project() rounds differently from the
  // walk; its error is many orders of magnitude smaller). A ray passing
  // near the eye fails (a point there projects anywhere).
  bool rest_is_background(const PreparedSample& s, const Vec3d& x, const Vec3d& dir) const {
    const Vec3d v0 = x - s.eye;
    const double along = dot(v0, dir);
    const double closest = along >= 0 ? length(v0) : length(v0 - dir * along);
    const double scale = length(v0) + length(x) + length(s.eye) + 1;  // of the coordinates' rounding
    if (!(closest > 1e-6 * scale)) return false;
    const double hair = 1e-12 * scale;
    for (int f = 0; f < kCubeFaces; ++f) {
      const FaceAxes& a = axes_[f];
      const double fw0 = a.fwd_sign * v0[a.fwd_axis], fwd = a.fwd_sign * dir[a.fwd_axis];
      const double r0 = a.right_sign * v0[a.right_axis], rd = a.right_sign * dir[a.right_axis];
      const double u0 = a.up_sign * v0[a.up_axis], ud = a.up_sign * dir[a.up_axis];
      // Inside the frustum: fw - r >= 0, fw + r >= 0, fw - up >= 0, fw + up >= 0 (so fw >= 0), less a hair.
      double lo = 0, hi = kInf;
      const double c[4] = {fw0 - r0 + hair, fw0 + r0 + hair, fw0 - u0 + hair, fw0 + u0 + hair};
      const double g[4] = {fwd - rd, fwd + rd, fwd - ud, fwd + ud};
      for (int h = 0; h < 4 && lo <= hi; ++h) {
        if (g[h] > 0) {
          lo = std::max(lo, -c[h] / g[h]);
        } else if (g[h] < 0) {
          hi = std::min(hi, -c[h] / g[h]);
        } else if (c[h] < 0) {
          hi = -1;
        }
      }
      if (!(lo <= hi)) continue;
      // Pixel coordinates (continuous, [0, n] up to the hair) of both ends.
      auto pixel_of = [&](double fw, double r, double up, double& pi, double& pj) {
        pi = s.half_n * (1 + r / fw);
        pj = s.half_n * (1 - up / fw);
      };
      double pi0, pj0, pi1, pj1;
      const double fw_lo = fw0 + lo * fwd;
      if (!(fw_lo > 0)) return false;
      pixel_of(fw_lo, r0 + lo * rd, u0 + lo * ud, pi0, pj0);
      if (hi == kInf) {
        pixel_of(fwd, rd, ud, pi1, pj1);  // the vanishing point
      } else {
        const double fw_hi = fw0 + hi * fwd;
        if (!(fw_hi > 0)) return false;
        pixel_of(fw_hi, r0 + hi * rd, u0 + hi * ud, pi1, pj1);
      }
      if (!segment_is_background(s, f, pi0, pj0, pi1, pj1)) return false;
    }
    return true;
  }

  // Pixels (a fraction) a cell's neighbour is also read within.
  static constexpr double kWalkMargin = 1e-3;

  // Walks the pixels of face f crossed by the segment (pi0, pj0)-(pi1, pj1)
  // in continuous pixel coordinates, with the neighbours whose border the
  // segment comes within kWalkMargin of; false at the first finite depth.
  static bool segment_is_background(const PreparedSample& s, int f, double pi0, double pj0, double pi1,
                                    double pj1) {
    const int n = s.n;
    auto cell = [n](double p) { return std::clamp(static_cast<int>(std::floor(p)), 0, n - 1); };
    int i = cell(pi0), j = cell(pj0);
    const int i_end = cell(pi1), j_end = cell(pj1);
    const double di = pi1 - pi0, dj = pj1 - pj0;
    const int step_i = di > 0 ? 1 : -1, step_j = dj > 0 ? 1 : -1;
    // Parameter (0..1 along the segment) of the next vertical / horizontal pixel border.
    const double inv_i = di != 0 ? 1 / std::fabs(di) : kInf, inv_j = dj != 0 ? 1 / std::fabs(dj) : kInf;
    double next_i = di != 0 ? (di > 0 ? (i + 1 - pi0) : (pi0 - i)) * inv_i : kInf;
    double next_j = dj != 0 ? (dj > 0 ? (j + 1 - pj0) : (pj0 - j)) * inv_j : kInf;
    const float* depth = s.depth[f];
    const auto background = [&](int ci, int cj) {
      return ci < 0 || cj < 0 || ci >= n || cj >= n ||
             !(depth[static_cast<std::size_t>(cj) * n + ci] < kBackgroundDepth);
    };
    double entry = 0;  // the segment's parameter where it enters cell (i, j)
    // At most |i_end - i| + |j_end - j| steps; an axis that has reached its
    // end cell no longer steps (rounding near a pixel corner).
    while (true) {
      if (!background(i, j)) return false;
      const bool last = i == i_end && j == j_end;
      const bool along_i = !last && (j == j_end || (i != i_end && next_i < next_j));
      const double exit = last ? 1.0 : std::min(along_i ? next_i : next_j, 1.0);
      // The segment's extent within this cell, and the neighbours it nearly touches.
      const double ia = pi0 + di * entry, ib = pi0 + di * exit, ja = pj0 + dj * entry, jb = pj0 + dj * exit;
      const int left = std::min(ia, ib) < i + kWalkMargin ? -1 : 0;
      const int right = std::max(ia, ib) > i + 1 - kWalkMargin ? 1 : 0;
      const int top = std::min(ja, jb) < j + kWalkMargin ? -1 : 0;
      const int bottom = std::max(ja, jb) > j + 1 - kWalkMargin ? 1 : 0;
      for (int nj = top; nj <= bottom; ++nj)
        for (int ni = left; ni <= right; ++ni)
          if ((ni != 0 || nj != 0) && !background(i + ni, j + nj)) return false;
      if (last) return true;
      entry = exit;
      if (along_i) {
        i += step_i;
        next_i += inv_i;
      } else {
        j += step_j;
        next_j += inv_j;
      }
    }
  }

  Vec3d candidate_;
  const VoidParams& params_;
  double max_distance_;
  std::array<FaceAxes, kCubeFaces> axes_;
  std::vector<PreparedSample> prepared_;
  std::vector<NearBall> near_;
  double first_t_ = 0;         // the first marching distance outside every sample's near ball
  double before_first_t_ = 0;  // the one before it, 0 when first_t_ = start_distance
  bool all_void_ = false;      // every sample's near ball is blocked
  std::vector<char> prev_certified_;
  std::vector<double> prev_depth_;
  std::vector<char> tried_background_;
};

void validate(const Vec3d& candidate, std::span<const VoidSample> samples, const VoidParams& p) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("void_fraction: " + what); };
  if (samples.empty()) fail("no samples");
  if (!is_finite(candidate)) fail("candidate is not finite");
  if (p.face_size < 1) fail("face_size must be >= 1");
  if (!(std::isfinite(p.step_ratio) && 1 + p.step_ratio > 1))
    fail("step_ratio must be finite and > 0 (and 1 + step_ratio > 1)");
  if (!(std::isfinite(p.start_distance) && p.start_distance > 0))
    fail("start_distance must be finite and > 0");
  if (!(std::isfinite(p.max_distance) && p.max_distance >= 0)) fail("max_distance must be finite and >= 0");
  if (!(std::isfinite(p.surface_tolerance) && p.surface_tolerance >= 0))
    fail("surface_tolerance must be finite and >= 0");
  if (!(std::isfinite(p.jump) && p.jump >= 0)) fail("jump must be finite and >= 0");
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const CubeSample* cube = samples[k].cube;
    const std::string name = "sample " + std::to_string(k);
    if (!cube) fail(name + " has no cube");
    if (!is_finite(cube->eye)) fail(name + " has a non-finite eye");
    const int n = cube->faces[0].size;
    if (n < 1) fail(name + " has empty faces");
    for (const CubeFace& face : cube->faces) {
      if (face.size != n) fail(name + " has faces of differing sizes");
      if (face.depth.size() != static_cast<std::size_t>(n) * n)
        fail(name + " has a depth array of the wrong length");
    }
  }
}

// The largest finite depth of a sample (0 when it sees only background).
// Non-negative floats order as their bit patterns; +inf is 0x7f800000 and
// NaNs lie above it, negative values below 0. (Integer max vectorises.)
double largest_finite_depth(const CubeSample& cube) {
  std::int32_t largest = 0;
  for (const CubeFace& face : cube.faces) {
    const float* depth = face.depth.data();
    for (std::size_t i = 0; i < face.depth.size(); ++i) {
      std::int32_t bits;
      std::memcpy(&bits, depth + i, sizeof bits);
      largest = std::max(largest, bits < 0x7f800000 ? bits : 0);
    }
  }
  float out;
  std::memcpy(&out, &largest, sizeof out);
  return out;
}

// Solid angle of the part of a cube face (forward component 1) over [s0, s1] x [t0, t1].
double face_solid_angle(double s0, double s1, double t0, double t1) {
  auto f = [](double s, double t) { return std::atan2(s * t, std::sqrt(1 + s * s + t * t)); };
  return f(s1, t1) - f(s0, t1) - f(s1, t0) + f(s0, t0);
}

// The march's last distance (see void_fraction's contract).
double resolved_max_distance(const Vec3d& candidate, std::span<const VoidSample> samples,
                             const VoidParams& params) {
  double max_distance = params.max_distance;
  if (max_distance == 0) {
    for (const VoidSample& s : samples)
      max_distance =
          std::max(max_distance, length(candidate - s.cube->eye) + 2 * largest_finite_depth(*s.cube));
  }
  return max_distance;
}

// Marches, in the fixed ray order, every ray that `seen` (null: none) does
// not mark as seen, and marks those it finds seen.
VoidResult march_rays(const Vec3d& candidate, std::span<const VoidSample> samples, const VoidParams& params,
                      double max_distance, std::vector<std::uint8_t>* seen) {
  const int n = params.face_size;
  std::vector<double> weight(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double s0 = 2.0 * i / n - 1, s1 = 2.0 * (i + 1) / n - 1;
      const double t0 = 1 - 2.0 * (j + 1) / n, t1 = 1 - 2.0 * j / n;
      weight[static_cast<std::size_t>(j) * n + i] = face_solid_angle(s0, s1, t0, t1);
    }

  Marcher marcher(candidate, samples, params, max_distance);
  VoidResult result;
  double void_weight = 0, total_weight = 0;
  std::size_t ray = 0;
  for (int f = 0; f < kCubeFaces; ++f) {
    const FaceBasis basis = cube_face_basis(f);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i, ++ray) {
        const double w = weight[static_cast<std::size_t>(j) * n + i];
        total_weight += w;
        ++result.rays;
        if (seen && (*seen)[ray]) continue;  // stays seen (VoidRayMemory)
        const double s = 2 * (i + 0.5) / n - 1, t = 1 - 2 * (j + 0.5) / n;
        const Vec3d d = cube_face_direction(basis, s, t);
        const RayVerdict verdict = marcher.march(d * (1 / length(d)));
        ++result.marched_rays;
        if (seen) (*seen)[ray] = verdict != RayVerdict::void_surface;
        if (verdict == RayVerdict::void_surface) {
          ++result.void_rays;
          void_weight += w;
        }
      }
  }
  result.fraction = std::clamp(void_weight / total_weight, 0.0, 1.0);
  return result;
}

}  // namespace

VoidResult void_fraction(const Vec3d& candidate, std::span<const VoidSample> samples,
                         const VoidParams& params) {
  validate(candidate, samples, params);
  return march_rays(candidate, samples, params, resolved_max_distance(candidate, samples, params), nullptr);
}

VoidResult void_fraction(const Vec3d& candidate, std::span<const VoidSample> samples,
                         const VoidParams& params, VoidRayMemory& memory) {
  validate(candidate, samples, params);
  const std::size_t rays =
      std::size_t(kCubeFaces) * std::size_t(params.face_size) * std::size_t(params.face_size);
  const double max_distance = resolved_max_distance(candidate, samples, params);
  const bool empty = memory.eyes.empty() && memory.seen_for_good.empty();
  if (!empty) {
    const auto fail = [](const std::string& what) {
      throw std::invalid_argument("void_fraction: the ray memory " + what);
    };
    if (!(memory.candidate == candidate)) fail("belongs to another candidate");
    const VoidParams& m = memory.params;
    if (m.face_size != params.face_size || m.step_ratio != params.step_ratio ||
        m.start_distance != params.start_distance || m.max_distance != params.max_distance ||
        m.surface_tolerance != params.surface_tolerance || m.jump != params.jump)
      fail("was learned with other params");
    if (memory.seen_for_good.size() != rays)
      fail("holds " + std::to_string(memory.seen_for_good.size()) + " rays, not " + std::to_string(rays));
    if (memory.eyes.size() > samples.size()) fail("knows more samples than are given");
    for (std::size_t k = 0; k < memory.eyes.size(); ++k)
      if (!(memory.eyes[k] == samples[k].cube->eye))
        fail("was learned with other samples (sample " + std::to_string(k) + ")");
  }
  const bool reuse = !empty && memory.max_distance == max_distance;
  if (!reuse) memory.seen_for_good.assign(rays, 0);
  const VoidResult result = march_rays(candidate, samples, params, max_distance, &memory.seen_for_good);
  memory.candidate = candidate;
  memory.params = params;
  memory.max_distance = max_distance;
  memory.eyes.clear();
  for (const VoidSample& s : samples) memory.eyes.push_back(s.cube->eye);
  return result;
}

}  // namespace cellbake
