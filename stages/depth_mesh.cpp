// Dense depth meshes without skins (Wilson 2002, ch. 5 §5.2.2; skin heuristics
// §3.4.2.1.1). See depth_mesh.h for the contract.
//
// Every pixel corner of the cube is a point of an integer lattice on the cube of
// half-size N (N = face size): direction D = N forward + (2 ci - N) right +
// (N - 2 cj) up. The pixels touching a lattice point are gathered from every
// face containing it (4 inside a face or on a cube edge, 3 at a cube corner),
// sorted, split into connected components by the skin test, and each component's
// depth at the corner is interpolated from its pixels (corner_inverse_depth):
// inside a face the mean inverse depth of 4 pixels, where the thesis averages
// depths; inverse depth is affine over a world plane in screen space, so planes
// seen at any angle, also across cube edges, give exactly coplanar corners,
// which the simplifier exploits.
// The vertex is then D * (depth / N): the same arithmetic on the same numbers
// for every face that shares the point, hence bit-identical positions.
//
// Cost: the skin test of every in-face neighbour pair (4 per pixel) is made
// once per face and cached as flags, with the face's surface points and screen
// coordinates; only the 4N corners on a face border gather and test their
// pixels across faces. Corners inside a face take their components from a
// 64-entry table indexed by the flags of their 6 pixel pairs, and their depth
// from the cached screen coordinates with corner_inverse_depth's arithmetic
// (the same bits); vertex ids live in two rows of pixels, the triangles of a
// row being written once its lower corners are known.
#include "stages/depth_mesh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace cellbake {
namespace {

using Lattice = std::array<long, 3>;

struct PixelRef {
  int face = 0, i = 0, j = 0;
  friend bool operator<(const PixelRef& a, const PixelRef& b) {
    if (a.face != b.face) return a.face < b.face;
    if (a.j != b.j) return a.j < b.j;
    return a.i < b.i;
  }
  friend bool operator==(const PixelRef&, const PixelRef&) = default;
};

// A pixel's surface point in a face's screen frame (CubeLattice::screen).
struct PixelScreen {
  double s, t, w;
};

}  // namespace

struct DepthMeshScratch::Buffers {
  std::vector<Vec3d> points;
  std::vector<double> distances;
  std::vector<PixelScreen> screens;
  std::array<std::vector<std::uint8_t>, kCubeFaces> flags;
};

DepthMeshScratch::DepthMeshScratch() = default;
DepthMeshScratch::~DepthMeshScratch() = default;
DepthMeshScratch::DepthMeshScratch(DepthMeshScratch&&) noexcept = default;
DepthMeshScratch& DepthMeshScratch::operator=(DepthMeshScratch&&) noexcept = default;

DepthMeshScratch::Buffers& DepthMeshScratch::buffers() {
  if (!buffers_) buffers_ = std::make_unique<Buffers>();
  return *buffers_;
}

namespace {

struct IntBasis {
  Lattice forward, right, up;
};

Lattice to_lattice(Vec3d v) { return {std::lround(v.x), std::lround(v.y), std::lround(v.z)}; }
long dot(const Lattice& a, const Lattice& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

class CubeLattice {
 public:
  // The cached face's per-pixel arrays live in `buffers` (reused as they are:
  // cache_face overwrites every element it later reads).
  CubeLattice(const CubeSample& sample, const DepthMeshParams& params, DepthMeshScratch::Buffers& buffers)
      : sample_(sample), n_(sample.faces[0].size), points_(buffers.points), distances_(buffers.distances),
        screens_(buffers.screens), flags_(buffers.flags) {
    for (int f = 0; f < kCubeFaces; ++f) {
      const FaceBasis b = cube_face_basis(f);
      basis_[f] = b;
      ibasis_[f] = {to_lattice(b.forward), to_lattice(b.right), to_lattice(b.up)};
    }
    for (const SkinWitness& w : params.witnesses) {
      if (!w.depth || w.size < 1) throw std::invalid_argument("depth mesh: a skin witness has no depths");
      for (const auto& face : *w.depth)
        if (face.size() != std::size_t(w.size) * std::size_t(w.size))
          throw std::invalid_argument("depth mesh: a skin witness's face is not size^2 depths");
      witnesses_.push_back({w.eye - sample.eye, w.depth, w.size});
    }
    witness_min_jump_ = params.witness_min_jump;
    witness_margin_ = params.witness_margin;
    angle_limit_ = params.skin_angle_degrees * 3.14159265358979323846 / 180.0;
    jump_limit_ = params.max_relative_depth_jump;
    if (angle_limit_ < 1.5) {
      const double tan_limit = std::tan(angle_limit_);
      tan_low_ = tan_limit * (1 - 1e-9);
      tan_high_ = tan_limit * (1 + 1e-9);
      squares_decide_ = tan_low_ >= 0 && std::isfinite(tan_high_);
    } else {  // near or past a right angle: always take the exact path
      tan_low_ = -1;
      tan_high_ = std::numeric_limits<double>::infinity();
    }
  }

  int size() const { return n_; }
  float depth(const PixelRef& p) const { return sample_.faces[p.face].depth[std::size_t(p.j) * n_ + p.i]; }
  bool background(const PixelRef& p) const { return !std::isfinite(depth(p)); }

  // Surface point of a pixel centre relative to the eye (from the cache when
  // the pixel is on the cached face: the same bits either way).
  Vec3d point(const PixelRef& p) const {
    if (p.face == cached_face_) return points_[std::size_t(p.j) * n_ + p.i];
    return compute_point(p);
  }

  // A pixel's surface point in the screen frame of face `frame`: s = right / z,
  // t = up / z, w = 1 / z with z = forward component (cached for the cached face).
  using Screen = PixelScreen;
  Screen screen(const PixelRef& p, int frame) const {
    if (p.face == cached_face_ && frame == cached_face_) return screens_[std::size_t(p.j) * n_ + p.i];
    return compute_screen(point(p), frame);
  }
  Screen compute_screen(const Vec3d& p, int frame) const {
    const FaceBasis& b = basis_[frame];
    const double z = cellbake::dot(p, b.forward);
    return {cellbake::dot(p, b.right) / z, cellbake::dot(p, b.up) / z, 1.0 / z};
  }

  // Caches the surface points of face f (replacing the previous face's) and
  // computes face f's skin flags (see skin_flags).
  void cache_face(int f) {
    cached_face_ = -1;
    const std::size_t count = std::size_t(n_) * n_;
    points_.resize(count);
    distances_.resize(count);
    screens_.resize(count);
    // compute_point's arithmetic with the pixel-centre coordinates taken once
    // per column and row (the same bits).
    column_s_.resize(n_);
    for (int i = 0; i < n_; ++i) column_s_[i] = 2.0 * (i + 0.5) / n_ - 1.0;
    const FaceBasis& b = basis_[f];
    const float* face_depth = sample_.faces[f].depth.data();
    for (int j = 0; j < n_; ++j) {
      const double t = 1.0 - 2.0 * (j + 0.5) / n_;
      for (int i = 0; i < n_; ++i) {
        const std::size_t k = std::size_t(j) * n_ + i;
        points_[k] = cube_face_direction(b, column_s_[i], t) * double(face_depth[k]);
        distances_[k] = length(points_[k]);
        screens_[k] = compute_screen(points_[k], f);
      }
    }
    cached_face_ = f;
    std::vector<std::uint8_t>& flags = flags_[f];
    flags.resize(count);  // every flag is written below
    const std::vector<float>& depth = sample_.faces[f].depth;
    auto pair_skin = [&](std::size_t a, int i, int j) {  // a before (i, j) in canonical order
      if (i < 0 || j < 0 || i >= n_ || j >= n_) return false;
      const std::size_t b = std::size_t(j) * n_ + i;
      if (!std::isfinite(depth[a]) || !std::isfinite(depth[b])) return true;
      return skin_between(points_[a], distances_[a], points_[b], distances_[b]);
    };
    for (int j = 0; j < n_; ++j)
      for (int i = 0; i < n_; ++i) {
        const std::size_t a = std::size_t(j) * n_ + i;
        flags[a] = std::uint8_t((pair_skin(a, i + 1, j) ? kSkinEast : 0) | (pair_skin(a, i, j + 1) ? kSkinSouth : 0) |
                                (pair_skin(a, i + 1, j + 1) ? kSkinSouthEast : 0) |
                                (pair_skin(a, i - 1, j + 1) ? kSkinSouthWest : 0));
      }
  }

  // Skin flags of face f's pixel (i, j) towards its neighbours (i+1, j),
  // (i, j+1), (i+1, j+1), (i-1, j+1), as skin() would answer (false where
  // the neighbour is off the face). Valid after cache_face(f).
  std::uint8_t skin_flags(int f, int i, int j) const { return flags_[f][std::size_t(j) * n_ + i]; }

  static constexpr std::uint8_t kSkinEast = 1, kSkinSouth = 2, kSkinSouthEast = 4, kSkinSouthWest = 8;

  // Row-major arrays of face f: depths, skin flags (valid after cache_face(f))
  // and, for the cached face, the screen coordinates of its pixels.
  const float* depths(int f) const { return sample_.faces[f].depth.data(); }
  const std::uint8_t* skin_flags_of(int f) const { return flags_[f].data(); }
  const Screen* cached_screens() const { return screens_.data(); }
  const IntBasis& int_basis(int f) const { return ibasis_[f]; }

 private:
  Vec3d compute_point(const PixelRef& p) const {
    const double s = 2.0 * (p.i + 0.5) / n_ - 1.0;
    const double t = 1.0 - 2.0 * (p.j + 0.5) / n_;
    return cube_face_direction(basis_[p.face], s, t) * double(depth(p));
  }

 public:

  // Skin test between neighbouring pixels; symmetric and deterministic (the
  // pair is put in canonical order before any arithmetic).
  bool skin(PixelRef a, PixelRef b) const {
    if (b < a) std::swap(a, b);
    if (background(a) || background(b)) return true;
    const Vec3d pa = point(a), pb = point(b);
    return skin_between(pa, length(pa), pb, length(pb));
  }

  // The skin test on the surface points of two covered pixels (a before b in
  // canonical order) and their eye distances. The angle test compares tangents
  // first and calls atan2 only within a relative 1e-9 of the limit, so the
  // decision is the same as atan2(|e x m|, |e . m|) < limit.
  bool skin_between(const Vec3d& pa, double da, const Vec3d& pb, double db) const {
    if (std::abs(da - db) > jump_limit_ * std::min(da, db)) return true;
    if (!witnesses_.empty() && std::abs(da - db) > witness_min_jump_ * std::min(da, db) &&
        witnessed_past((pa + pb) * 0.5))
      return true;
    const Vec3d e = pb - pa;
    const Vec3d m = (pa + pb) * 0.5;
    const Vec3d c = cross(e, m);
    const double across_squared = cellbake::dot(c, c), along = std::abs(cellbake::dot(e, m));
    if (squares_decide_) {
      // Most pairs are far from the limit: decide on the squares (no square
      // root) where they clear it by a relative 1e-12, far above rounding, so
      // the decision is the one below; normal squares only (no underflow).
      const double low = tan_low_ * along, high = tan_high_ * along;
      const double low_squared = low * low, high_squared = high * high;
      constexpr double kNormal = std::numeric_limits<double>::min();
      if (low_squared >= kNormal && across_squared < low_squared * (1 - 1e-12)) return true;
      if (high_squared >= kNormal && across_squared > high_squared * (1 + 1e-12)) return false;
    }
    const double across = std::sqrt(across_squared);
    if (across < tan_low_ * along) return true;
    if (across > tan_high_ * along) return false;
    return std::atan2(across, along) < angle_limit_;
  }

  // Whether a witness sees past the point `m` (relative to this sample's eye):
  // all four of its pixels around m's projection lie beyond m (DepthMeshParams).
  bool witnessed_past(const Vec3d& m) const {
    for (const Witness& w : witnesses_) {
      const Vec3d d = m - w.offset;  // m relative to the witness's eye
      const int f = major_face(d);
      const FaceBasis& b = basis_[f];
      const double z = cellbake::dot(d, b.forward);
      if (!(z > 0)) continue;
      const double s = cellbake::dot(d, b.right) / z, t = cellbake::dot(d, b.up) / z;
      // The 2x2 pixels whose centres surround (s, t); a projection within a
      // pixel of the face's border is not judged (no block surrounds it).
      const double x = (s + 1) * 0.5 * w.size - 0.5, y = (1 - t) * 0.5 * w.size - 0.5;
      if (!(x >= 1 && y >= 1 && x <= w.size - 2 && y <= w.size - 2)) continue;
      const int i0 = int(std::floor(x)), j0 = int(std::floor(y));
      const std::vector<float>& depth = (*w.depth)[std::size_t(f)];
      const double beyond = z * (1 + witness_margin_);
      const auto past = [&](int i, int j) { return double(depth[std::size_t(j) * w.size + i]) > beyond; };
      if (past(i0, j0) && past(i0 + 1, j0) && past(i0, j0 + 1) && past(i0 + 1, j0 + 1)) return true;
    }
    return false;
  }

  // The cube face whose frustum holds direction d (the largest component's axis and sign).
  int major_face(const Vec3d& d) const {
    int best = 0;
    double best_dot = -std::numeric_limits<double>::infinity();
    for (int f = 0; f < kCubeFaces; ++f) {
      const double v = cellbake::dot(d, basis_[f].forward);
      if (v > best_dot) best_dot = v, best = f;
    }
    return best;
  }

  // Lattice direction of corner (ci, cj) of face f.
  Lattice corner(int f, int ci, int cj) const {
    const IntBasis& b = ibasis_[f];
    Lattice d{};
    for (int k = 0; k < 3; ++k) d[k] = long(n_) * b.forward[k] + long(2 * ci - n_) * b.right[k] + long(n_ - 2 * cj) * b.up[k];
    return d;
  }

  // All pixels of all faces touching lattice point d, sorted.
  void gather(const Lattice& d, std::vector<PixelRef>& out) const {
    out.clear();
    for (int g = 0; g < kCubeFaces; ++g) {
      const IntBasis& b = ibasis_[g];
      if (dot(d, b.forward) != n_) continue;
      const long ci = (dot(d, b.right) + n_) / 2, cj = (n_ - dot(d, b.up)) / 2;
      for (long j = cj - 1; j <= cj; ++j)
        for (long i = ci - 1; i <= ci; ++i)
          if (i >= 0 && j >= 0 && i < n_ && j < n_) out.push_back({g, int(i), int(j)});
    }
    std::sort(out.begin(), out.end());
  }

  // Whether lattice point d is on a cube edge (two coordinates at +-N).
  bool on_cube_edge(const Lattice& d) const {
    int at_n = 0;
    for (long c : d) at_n += (std::abs(c) == n_);
    return at_n >= 2;
  }

 private:
  const CubeSample& sample_;
  int n_;
  double angle_limit_ = 0, jump_limit_ = 0, tan_low_ = 0, tan_high_ = 0;
  bool squares_decide_ = false;  // skin_between may decide on squared lengths
  struct Witness {
    Vec3d offset;  // the witness's eye relative to this sample's
    const std::array<std::vector<float>, kCubeFaces>* depth;
    int size;
  };
  std::vector<Witness> witnesses_;
  double witness_min_jump_ = 0, witness_margin_ = 0;
  std::array<FaceBasis, kCubeFaces> basis_;
  std::array<IntBasis, kCubeFaces> ibasis_;
  int cached_face_ = -1;
  std::vector<Vec3d>& points_;
  std::vector<double>& distances_;
  std::vector<Screen>& screens_;
  std::vector<double> column_s_;
  std::array<std::vector<std::uint8_t>, kCubeFaces>& flags_;
};

// Connected components (labels 0..k-1, by first occurrence) of the pixels
// touching one lattice point; pairs are all 8-neighbours of each other.
struct Corner {
  std::vector<PixelRef> pixels;
  std::array<int, 4> label{};
  std::array<bool, 6> pair_connected{};  // pairs in order (0,1) (0,2) (0,3) (1,2) (1,3) (2,3)
  int components = 0;
  std::array<PixelRef, 20> fit;  // scratch for corner_inverse_depth: at most 4 pixels and 4 neighbours of each
};

int pair_index(int a, int b) {
  static constexpr int table[4][4] = {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}};
  return table[a][b];
}

// `connected(a, b)` says whether pixels a < b (of n) of the corner are not a skin.
template <class Connected>
void analyse_corner_with(Corner& c, int n, Connected connected_pair) {
  std::array<int, 4> parent{0, 1, 2, 3};
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x];
    return x;
  };
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const bool connected = connected_pair(a, b);
      c.pair_connected[pair_index(a, b)] = connected;
      if (connected) {
        const int ra = find(a), rb = find(b);
        parent[std::max(ra, rb)] = std::min(ra, rb);
      }
    }
  std::array<int, 4> root_label{-1, -1, -1, -1};
  c.components = 0;
  for (int a = 0; a < n; ++a) {
    const int r = find(a);
    if (root_label[r] < 0) root_label[r] = c.components++;
    c.label[a] = root_label[r];
  }
}

void analyse_corner(const CubeLattice& lat, Corner& c) {
  analyse_corner_with(c, int(c.pixels.size()), [&](int a, int b) { return !lat.skin(c.pixels[a], c.pixels[b]); });
}

// Component labels of the 4 pixels NW, NE, SW, SE of a corner inside a face,
// indexed by its skin bits in pair order (bit 0 = NW-NE, 1 = NW-SW, 2 = NW-SE,
// 3 = NE-SW, 4 = NE-SE, 5 = SW-SE): analyse_corner_with's labels, tabulated.
using InteriorCornerLabels = std::array<std::array<std::uint8_t, 4>, 64>;

InteriorCornerLabels interior_corner_labels() {
  InteriorCornerLabels table{};
  Corner c;
  for (unsigned skins = 0; skins < 64; ++skins) {
    analyse_corner_with(c, 4, [&](int a, int b) { return !(skins >> pair_index(a, b) & 1u); });
    for (int a = 0; a < 4; ++a) table[skins][a] = std::uint8_t(c.label[a]);
  }
  return table;
}

// True when a cube-edge lattice point is fully connected (see depth_mesh.h).
bool edge_point_fully_connected(const Corner& c) {
  // Sorted by face: pixels 0, 1 lie on one face and 2, 3 on the other.
  return c.pixels.size() == 4 && c.components == 1 && c.pair_connected[pair_index(0, 1)] &&
         c.pair_connected[pair_index(2, 3)];
}

// Inverse depth at the corner ray D of component l of corner c: the pixels'
// surface points are expressed in the screen frame of the component's lowest
// face (s, t, w = 1 / planar depth; w is affine in (s, t) over any world plane,
// also beyond the face border), and w at the corner is read from the plane
// fitted to them (least squares; exact for 3 pixels; the mean for 1 or 2). For
// 4 pixels of one face this is their mean inverse depth, for 3 it interpolates
// the two pixels diagonal to each other: a world plane gives exactly coplanar
// corners. Across cube edges the fit also takes the pixels' 4-neighbours on
// their faces and is used only when all those points fit one plane (to rounding);
// otherwise (a crease along the edge, a curved surface) the corner takes the
// mean of each pixel's inverse depth in its own face's frame. Deterministic: the same sorted pixels and
// frame give the same bits for every face sharing the corner.
double corner_inverse_depth(const CubeLattice& lat, Corner& c, int l, const Lattice& d) {
  std::array<PixelRef, 20>& fit = c.fit;
  int fit_count = 0;
  int frame = kCubeFaces;
  bool one_face = true;
  for (std::size_t a = 0; a < c.pixels.size(); ++a)
    if (c.label[a] == l) {
      if (fit_count > 0 && c.pixels[a].face != fit[fit_count - 1].face) one_face = false;
      frame = std::min(frame, c.pixels[a].face);
      fit[fit_count++] = c.pixels[a];
    }
  const int k = fit_count;
  // Mean of the pixels' inverse depths, each in its own face's frame (the frames
  // of all faces through D agree on the corner ray itself).
  double own_mean = 0;
  for (int a = 0; a < k; ++a) own_mean += 1.0 / double(lat.depth(fit[a]));
  own_mean /= k;
  if (!one_face) {
    // Across a cube edge, 2 pixels per face lie on two lines parallel to the
    // edge, which always fit a plane, and the 3 pixels at a cube corner always
    // do: add the pixels' 4-neighbours on their own faces so that a plane can be
    // told from a crease along the edge (the corner of a room).
    const int n = lat.size();
    for (int a = 0; a < k; ++a) {
      const PixelRef p = fit[a];
      for (PixelRef q : {PixelRef{p.face, p.i - 1, p.j}, PixelRef{p.face, p.i + 1, p.j}, PixelRef{p.face, p.i, p.j - 1},
                         PixelRef{p.face, p.i, p.j + 1}})
        if (q.i >= 0 && q.j >= 0 && q.i < n && q.j < n && !lat.background(q) &&
            std::find(fit.begin(), fit.begin() + fit_count, q) == fit.begin() + fit_count)
          fit[fit_count++] = q;
    }
  }
  const FaceBasis b = cube_face_basis(frame);
  const double n = lat.size();
  const double s0 = (d[0] * b.right.x + d[1] * b.right.y + d[2] * b.right.z) / n;
  const double t0 = (d[0] * b.up.x + d[1] * b.up.y + d[2] * b.up.z) / n;
  struct Sample {
    double s, t, w;
  };
  std::array<Sample, 20> samples;
  int sample_count = 0;
  double m00 = 0, m01 = 0, m02 = 0, m11 = 0, m12 = 0, m22 = 0, r0 = 0, r1 = 0, r2 = 0;
  for (int a = 0; a < fit_count; ++a) {
    const CubeLattice::Screen& q = lat.screen(fit[a], frame);
    const Sample x{q.s - s0, q.t - t0, q.w};
    samples[sample_count++] = x;
    m00 += 1, m01 += x.s, m02 += x.t, m11 += x.s * x.s, m12 += x.s * x.t, m22 += x.t * x.t;
    r0 += x.w, r1 += x.s * x.w, r2 += x.t * x.w;
  }
  if (k < 3 && one_face) return r0 / m00;  // 1 or 2 pixels of one face: their mean
  const double det = m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02);
  if (!(std::abs(det) > 1e-12 * std::max(1.0, m11 * m22))) return own_mean;
  const double w0 = (r0 * (m11 * m22 - m12 * m12) - m01 * (r1 * m22 - m12 * r2) + m02 * (r1 * m12 - m11 * r2)) / det;
  const double w1 = (m00 * (r1 * m22 - m12 * r2) - r0 * (m01 * m22 - m12 * m02) + m02 * (m01 * r2 - r1 * m02)) / det;
  const double w2 = (m00 * (m11 * r2 - r1 * m12) - m01 * (m01 * r2 - r1 * m02) + r0 * (m01 * m12 - m11 * m02)) / det;
  if (!one_face) {
    // Across a cube edge the pixels may lie on two surfaces meeting at the edge
    // (a crease, e.g. the walls of a room seen from its centre): there the
    // fitted plane is wrong and each face's own inverse depth is right.
    double worst = 0;
    for (int a = 0; a < sample_count; ++a) {
      const Sample& x = samples[a];
      worst = std::max(worst, std::abs(w0 + w1 * x.s + w2 * x.t - x.w));
    }
    if (!(worst <= 1e-6 * own_mean)) return own_mean;
  }
  return w0 > 0 ? w0 : own_mean;
}

bool cube_corner_fully_connected(const CubeLattice& lat, const Lattice& d) {
  Corner c;
  lat.gather(d, c.pixels);
  if (c.pixels.size() != 3) return false;
  for (const PixelRef& p : c.pixels)
    if (lat.background(p)) return false;
  analyse_corner(lat, c);
  return c.pair_connected[0] && c.pair_connected[1] && c.pair_connected[3];
}

void validate(const CubeSample& sample) {
  const int n = sample.faces[0].size;
  if (n <= 0) throw std::invalid_argument("build_depth_meshes: face 0 has size " + std::to_string(n));
  for (int f = 0; f < kCubeFaces; ++f) {
    const CubeFace& face = sample.faces[f];
    if (face.size != n)
      throw std::invalid_argument("build_depth_meshes: face " + std::to_string(f) + " has size " +
                                  std::to_string(face.size) + ", face 0 has " + std::to_string(n));
    if (face.depth.size() != std::size_t(n) * n)
      throw std::invalid_argument("build_depth_meshes: face " + std::to_string(f) + " holds " +
                                  std::to_string(face.depth.size()) + " depths, expected " + std::to_string(n * n));
    // A branch-free scan first (it vectorises; the bake validates each sample
    // once per face it meshes), then the first bad pixel for the message.
    bool all_positive = true;
    for (const float z : face.depth) all_positive &= z > 0;  // false for NaN
    if (all_positive) continue;
    for (std::size_t k = 0; k < face.depth.size(); ++k) {
      const float z = face.depth[k];
      if (std::isnan(z) || !(z > 0))
        throw std::invalid_argument("build_depth_meshes: face " + std::to_string(f) + " pixel (" +
                                    std::to_string(k % n) + ", " + std::to_string(k / n) + ") has depth " +
                                    std::to_string(z) + " (must be positive or +inf)");
    }
  }
}

constexpr std::uint32_t kNone = 0xffffffffu;

// Inverse planar depth at an interior corner of the cached face for one
// component of k (1 to 4) pixels of that face, listed in canonical order by
// their indices into the face: corner_inverse_depth's one-face case, the same
// arithmetic in the same order (hence the same bits), without the unused
// slopes of the plane fit; the mean inverse depth is computed only when needed.
inline double interior_inverse_depth(const CubeLattice::Screen* screens, const float* depth, const std::size_t* pixel, int k,
                              double s0, double t0) {
  double m00 = 0, m01 = 0, m02 = 0, m11 = 0, m12 = 0, m22 = 0, r0 = 0, r1 = 0, r2 = 0;
  for (int a = 0; a < k; ++a) {
    const CubeLattice::Screen& q = screens[pixel[a]];
    const double s = q.s - s0, t = q.t - t0, w = q.w;
    m00 += 1, m01 += s, m02 += t, m11 += s * s, m12 += s * t, m22 += t * t;
    r0 += w, r1 += s * w, r2 += t * w;
  }
  if (k < 3) return r0 / m00;
  auto own_mean = [&] {
    double sum = 0;
    for (int a = 0; a < k; ++a) sum += 1.0 / double(depth[pixel[a]]);
    return sum / k;
  };
  const double det = m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02);
  if (!(std::abs(det) > 1e-12 * std::max(1.0, m11 * m22))) return own_mean();
  const double w0 = (r0 * (m11 * m22 - m12 * m12) - m01 * (r1 * m22 - m12 * r2) + m02 * (r1 * m12 - m11 * r2)) / det;
  return w0 > 0 ? w0 : own_mean();
}

// Vertex ids of one row of pixels at their corners NW, NE, SW, SE.
using PixelCorners = std::array<std::uint32_t, 4>;

// Appends the vertex at lattice point d (pixel corner (ci, cj) of face f) with
// inverse planar depth w.
inline std::uint32_t add_vertex(FaceMesh& mesh, const Lattice& d, double w, int n, int ci, int cj, float inv_n) {
  const double scale = (1.0 / w) / double(n);
  mesh.positions.push_back({float(double(d[0]) * scale), float(double(d[1]) * scale), float(double(d[2]) * scale)});
  mesh.uvs.push_back({float(ci) * inv_n, float(cj) * inv_n});
  return std::uint32_t(mesh.positions.size() - 1);
}

// One corner on the border of face f (gathered across faces, see depth_mesh.h);
// records its vertex ids in the rows of pixels above (`north`) and below
// (`south`) corner row cj.
void border_corner(const CubeLattice& lat, int f, int ci, int cj, Corner& c, FaceMesh& mesh, PixelCorners* north,
                   PixelCorners* south) {
  const int n = lat.size();
  const Lattice d = lat.corner(f, ci, cj);
  lat.gather(d, c.pixels);
  analyse_corner(lat, c);
  const int count = int(c.pixels.size());
  // Per-pixel records at cube-edge points that are not fully connected.
  bool split_per_pixel = false;
  if (count == 4 && lat.on_cube_edge(d)) {
    split_per_pixel = !edge_point_fully_connected(c);
    if (!split_per_pixel) {
      // Next to a cube corner along this edge?
      int free_axis = 0;
      for (int k = 0; k < 3; ++k)
        if (std::abs(d[k]) != n) free_axis = k;
      if (std::abs(d[free_axis]) == n - 2) {
        Lattice cube_corner = d;
        cube_corner[free_axis] = d[free_axis] > 0 ? n : -n;
        split_per_pixel = !cube_corner_fully_connected(lat, cube_corner);
      }
    }
  }
  // Inverse planar depth of each component at the corner ray.
  std::array<double, 4> corner_w{};
  for (int l = 0; l < c.components; ++l) corner_w[l] = corner_inverse_depth(lat, c, l, d);
  std::array<std::uint32_t, 4> component_vertex{kNone, kNone, kNone, kNone};
  const float inv_n = 1.0f / float(n);
  for (int a = 0; a < count; ++a) {
    const PixelRef& p = c.pixels[a];
    if (p.face != f || lat.background(p)) continue;
    const int l = c.label[a];
    std::uint32_t id = split_per_pixel ? kNone : component_vertex[l];
    if (id == kNone) {
      id = add_vertex(mesh, d, corner_w[l], n, ci, cj, inv_n);
      if (!split_per_pixel) component_vertex[l] = id;
    }
    const int slot = (cj - p.j) * 2 + (ci - p.i);
    (p.j < cj ? north : south)[p.i][slot] = id;
  }
}

FaceMesh build_face(const CubeLattice& lat, const InteriorCornerLabels& interior_labels, int f) {
  const int n = lat.size();
  const float* depth = lat.depths(f);
  const std::uint8_t* flags = lat.skin_flags_of(f);
  const CubeLattice::Screen* screens = lat.cached_screens();
  FaceMesh mesh;
  std::size_t covered = 0;
  for (std::size_t k = 0; k < std::size_t(n) * n; ++k) covered += std::isfinite(depth[k]);
  if (covered == 0) return mesh;
  mesh.positions.reserve(covered + 2 * std::size_t(n) + 1);
  mesh.uvs.reserve(covered + 2 * std::size_t(n) + 1);
  mesh.indices.reserve(6 * covered);
  // Vertex ids of the pixel rows above and below the current corner row.
  std::vector<PixelCorners> north(n, {kNone, kNone, kNone, kNone}), south(n, {kNone, kNone, kNone, kNone});
  Corner c;
  const float inv_n = 1.0f / float(n);
  const double nd = n;
  // Screen coordinates of the corners (corner_inverse_depth's s0 and t0: the
  // dot products of the integer corner direction with the axis-aligned basis
  // are exactly 2 ci - n and n - 2 cj; a zero's sign cannot matter as no pixel
  // centre has a zero screen coordinate where a corner does).
  std::vector<double> column_s0(n + 1);
  for (int ci = 0; ci <= n; ++ci) column_s0[ci] = double(2 * ci - n) / nd;
  for (int cj = 0; cj <= n; ++cj) {
    if (cj > 0) std::fill(south.begin(), south.end(), PixelCorners{kNone, kNone, kNone, kNone});
    border_corner(lat, f, 0, cj, c, mesh, north.data(), south.data());
    if (cj == 0 || cj == n) {
      for (int ci = 1; ci < n; ++ci) border_corner(lat, f, ci, cj, c, mesh, north.data(), south.data());
    } else {
      // Interior corners: pixels NW, NE, SW, SE of this face, connectivity from
      // the cached skin flags, one vertex per
      // component that holds a covered pixel.
      const std::size_t row_n = std::size_t(cj - 1) * n, row_s = std::size_t(cj) * n;
      const Lattice row_d = lat.corner(f, 0, cj);
      const Lattice& right = lat.int_basis(f).right;
      const double t0 = double(n - 2 * cj) / nd;
      for (int ci = 1; ci < n; ++ci) {
        const std::array<std::size_t, 4> px{row_n + ci - 1, row_n + ci, row_s + ci - 1, row_s + ci};
        const std::array<bool, 4> covered_px{std::isfinite(depth[px[0]]), std::isfinite(depth[px[1]]),
                                             std::isfinite(depth[px[2]]), std::isfinite(depth[px[3]])};
        if (!(covered_px[0] | covered_px[1] | covered_px[2] | covered_px[3])) continue;
        const std::uint8_t nw = flags[px[0]], ne = flags[px[1]], sw = flags[px[2]];
        const unsigned skins = unsigned(nw & CubeLattice::kSkinEast) | unsigned(nw & CubeLattice::kSkinSouth) |
                               unsigned(nw & CubeLattice::kSkinSouthEast) |
                               (ne & CubeLattice::kSkinSouthWest ? 8u : 0u) |
                               (ne & CubeLattice::kSkinSouth ? 16u : 0u) | (sw & CubeLattice::kSkinEast ? 32u : 0u);
        const std::array<std::uint8_t, 4>& label = interior_labels[skins];
        Lattice d;
        for (int k = 0; k < 3; ++k) d[k] = row_d[k] + long(2 * ci) * right[k];
        const double s0 = column_s0[ci];
        if (skins == 0) {  // the common case: four covered pixels, one component
          const std::uint32_t id =
              add_vertex(mesh, d, interior_inverse_depth(screens, depth, px.data(), 4, s0, t0), n, ci, cj, inv_n);
          north[ci - 1][3] = id, north[ci][2] = id, south[ci - 1][1] = id, south[ci][0] = id;
          continue;
        }
        std::array<std::uint32_t, 4> component_vertex{kNone, kNone, kNone, kNone};
        for (int a = 0; a < 4; ++a) {
          if (!covered_px[a]) continue;
          const int l = label[a];
          std::uint32_t id = component_vertex[l];
          if (id == kNone) {
            std::array<std::size_t, 4> members;
            int k = 0;
            for (int m = 0; m < 4; ++m)
              if (label[m] == l) members[k++] = px[m];
            id = add_vertex(mesh, d, interior_inverse_depth(screens, depth, members.data(), k, s0, t0), n, ci, cj,
                            inv_n);
            component_vertex[l] = id;
          }
          if (a < 2)
            north[ci - 1 + a][2 + (1 - a)] = id;  // NW pixel: its SE corner; NE pixel: its SW corner
          else
            south[ci - 1 + (a - 2)][1 - (a - 2)] = id;  // SW pixel: its NE corner; SE pixel: its NW corner
        }
      }
    }
    border_corner(lat, f, n, cj, c, mesh, north.data(), south.data());
    if (cj > 0)
      for (int i = 0; i < n; ++i) {
        const PixelCorners& v = north[i];
        if (v[0] == kNone) continue;  // background pixel
        mesh.indices.insert(mesh.indices.end(), {v[0], v[2], v[3], v[0], v[3], v[1]});
      }
    std::swap(north, south);
  }
  return mesh;
}

// Unique skin edges over the whole cube: pairs inside a face from a scan of
// each face, pairs across faces from the lattice points on cube edges.
std::size_t count_skin_edges(const CubeLattice& lat) {
  const int n = lat.size();
  std::size_t skins = 0;
  for (int f = 0; f < kCubeFaces; ++f)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) skins += std::popcount(unsigned(lat.skin_flags(f, i, j)));
  std::vector<std::pair<PixelRef, PixelRef>> cross_pairs;
  std::vector<PixelRef> pixels;
  for (int f = 0; f < kCubeFaces; ++f)
    for (int k = 0; k <= n; ++k)
      for (auto [ci, cj] : {std::pair{k, 0}, std::pair{k, n}, std::pair{0, k}, std::pair{n, k}}) {
        lat.gather(lat.corner(f, ci, cj), pixels);
        for (std::size_t a = 0; a < pixels.size(); ++a)
          for (std::size_t b = a + 1; b < pixels.size(); ++b)
            if (pixels[a].face != pixels[b].face) cross_pairs.emplace_back(pixels[a], pixels[b]);
      }
  std::sort(cross_pairs.begin(), cross_pairs.end(), [](const auto& x, const auto& y) {
    if (!(x.first == y.first)) return x.first < y.first;
    return x.second < y.second;
  });
  cross_pairs.erase(std::unique(cross_pairs.begin(), cross_pairs.end()), cross_pairs.end());
  for (const auto& [a, b] : cross_pairs) skins += lat.skin(a, b);
  return skins;
}

}  // namespace

std::array<FaceMesh, kCubeFaces> build_depth_meshes(const CubeSample& sample, const DepthMeshParams& params,
                                                    DepthMeshStats* stats) {
  validate(sample);
  DepthMeshScratch scratch;
  CubeLattice lat(sample, params, scratch.buffers());
  const InteriorCornerLabels interior_labels = interior_corner_labels();
  std::array<FaceMesh, kCubeFaces> meshes;
  for (int f = 0; f < kCubeFaces; ++f) {
    lat.cache_face(f);
    meshes[f] = build_face(lat, interior_labels, f);
  }
  if (stats) {
    *stats = {};
    for (int f = 0; f < kCubeFaces; ++f) {
      stats->triangles += meshes[f].triangle_count();
      for (float z : sample.faces[f].depth) stats->background_pixels += !std::isfinite(z);
    }
    stats->skin_edges = count_skin_edges(lat);
  }
  return meshes;
}

std::uint64_t outline_edge_guess(const CubeFace& face, const DepthMeshParams& params) {
  const int n = face.size;
  if (n <= 0 || face.depth.size() != std::size_t(n) * std::size_t(n)) return 0;
  const float jump = float(params.max_relative_depth_jump);
  const auto cut = [jump](float a, float b) {
    const bool fa = std::isfinite(a), fb = std::isfinite(b);
    if (fa != fb) return true;
    if (!fa) return false;
    return std::abs(a - b) > jump * std::min(a, b);
  };
  std::uint64_t edges = 0;
  for (int j = 0; j < n; ++j) {
    const float* row = face.depth.data() + std::size_t(j) * std::size_t(n);
    const float* below = j + 1 < n ? row + n : nullptr;
    for (int i = 0; i < n; ++i) {
      if (i + 1 < n) edges += cut(row[i], row[i + 1]);
      if (below) edges += cut(row[i], below[i]);
    }
  }
  return edges;
}

FaceMesh build_depth_mesh_face(const CubeSample& sample, const DepthMeshParams& params, int face,
                               DepthMeshScratch* scratch) {
  if (face < 0 || face >= kCubeFaces)
    throw std::invalid_argument("build_depth_mesh_face: no cube face " + std::to_string(face));
  validate(sample);
  DepthMeshScratch own;
  CubeLattice lat(sample, params, (scratch ? *scratch : own).buffers());
  lat.cache_face(face);
  return build_face(lat, interior_corner_labels(), face);
}

}  // namespace cellbake
