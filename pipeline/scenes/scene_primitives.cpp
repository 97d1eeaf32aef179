#include "pipeline/scenes/scene_primitives.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "pipeline/scenes/scene_math.h"

namespace cellbake {
namespace {

std::uint32_t next_index(const TriangleMesh& mesh) {
  return static_cast<std::uint32_t>(mesh.positions.size());
}

void push_vertex(TriangleMesh& mesh, Vec3d p, Rgba8 color) {
  mesh.positions.push_back(p);
  mesh.colors.push_back(color);
}

void push_triangle(TriangleMesh& mesh, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  mesh.indices.push_back(a);
  mesh.indices.push_back(b);
  mesh.indices.push_back(c);
}

// Cosine/sine of j/segments turns for j in [0, segments).
std::vector<SinCos> circle_table(int segments) {
  std::vector<SinCos> table(static_cast<std::size_t>(segments));
  for (int j = 0; j < segments; ++j)
    table[static_cast<std::size_t>(j)] = sin_cos_turns(static_cast<double>(j) / segments);
  return table;
}

void push_ring(TriangleMesh& mesh, Vec3d center, Vec3d u, Vec3d v, double radius,
               const std::vector<SinCos>& circle, Rgba8 color) {
  for (const SinCos& cs : circle)
    push_vertex(mesh, center + u * (radius * cs.c) + v * (radius * cs.s), color);
}

// Joins ring `a` (first vertex index) to the next ring `b` along the tangent direction.
void join_rings(TriangleMesh& mesh, std::uint32_t a, std::uint32_t b, int segments) {
  const auto n = static_cast<std::uint32_t>(segments);
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t j1 = (j + 1) % n;
    push_triangle(mesh, a + j, a + j1, b + j1);
    push_triangle(mesh, a + j, b + j1, b + j);
  }
}

void check_segments(int segments, const char* what) {
  if (segments < 3)
    throw std::invalid_argument(std::string(what) + ": needs at least 3 segments around, got " +
                                std::to_string(segments));
}

// ---- pipe planning, shared by pipe_size and append_pipe ----

struct PipeRing {
  Vec3d center, tangent, u;
};

constexpr std::uint64_t kMaxPiecesPerLeg = 1'000'000;

// Walks the rings of the swept tube in order and hands each to `ring`.
template <typename RingVisitor>
void plan_pipe(std::span<const Vec3d> path, const PipeStyle& style, RingVisitor&& ring) {
  const std::size_t n = path.size();
  if (n < 2) throw std::invalid_argument("pipe: path needs at least 2 points, got " + std::to_string(n));
  check_segments(style.segments, "pipe");
  if (!(style.radius > 0)) throw std::invalid_argument("pipe: radius must be positive");
  if (n > 2 && (style.bend_segments < 1 || !(style.bend_radius >= 1.2 * style.radius)))
    throw std::invalid_argument("pipe: bends need bend_segments >= 1 and bend_radius >= 1.2 * radius");

  auto leg_length = [&](std::size_t i) { return length(path[i + 1] - path[i]); };
  auto leg_dir = [&](std::size_t i) { return normalized(path[i + 1] - path[i]); };
  // Bend at interior point k (1..n-2), between legs k-1 and k.
  auto bend_radius_at = [&](std::size_t k) {
    if (k == 0 || k + 1 >= n) return 0.0;
    const double r = std::min({style.bend_radius, 0.45 * leg_length(k - 1), 0.45 * leg_length(k)});
    if (r < 1.2 * style.radius)
      throw std::invalid_argument("pipe: leg next to point " + std::to_string(k) +
                                  " is too short for a bend of a pipe of radius " +
                                  std::to_string(style.radius));
    return r;
  };

  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!(leg_length(i) > 0))
      throw std::invalid_argument("pipe: zero-length leg at point " + std::to_string(i));
    if (i + 2 < n && std::fabs(dot(leg_dir(i), leg_dir(i + 1))) > 1e-9)
      throw std::invalid_argument("pipe: legs at point " + std::to_string(i + 1) +
                                  " are not at a right angle");
  }

  Vec3d u = any_perpendicular(leg_dir(0));
  double bend_in = 0;  // bend radius consumed at the start of the current leg
  ring(PipeRing{path[0], leg_dir(0), u});
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const Vec3d d0 = leg_dir(i);
    const double bend_out = bend_radius_at(i + 1);
    const Vec3d start = path[i] + d0 * bend_in;
    const double straight = leg_length(i) - bend_in - bend_out;
    std::uint64_t pieces = 1;
    if (style.max_piece_length > 0)
      pieces = static_cast<std::uint64_t>(
          std::min(std::ceil(straight / style.max_piece_length), static_cast<double>(kMaxPiecesPerLeg)));
    pieces = std::max<std::uint64_t>(pieces, 1);
    for (std::uint64_t k = 1; k <= pieces; ++k)
      ring(PipeRing{start + d0 * (straight * static_cast<double>(k) / static_cast<double>(pieces)), d0, u});
    if (bend_out > 0) {
      const Vec3d d1 = leg_dir(i + 1);
      const Vec3d axis = cross(d0, d1);
      const Vec3d bend_start = path[i + 1] - d0 * bend_out;
      const Vec3d arc_center = bend_start + d1 * bend_out;
      for (int k = 1; k <= style.bend_segments; ++k) {
        const SinCos phi = sin_cos_turns(0.25 * k / style.bend_segments);
        const Vec3d center = arc_center + (d1 * -phi.c + d0 * phi.s) * bend_out;
        ring(PipeRing{center, d0 * phi.c + d1 * phi.s, rotate_about(u, axis, phi)});
      }
      u = rotate_about(u, axis, sin_cos_turns(0.25));
    }
    bend_in = bend_out;
  }
}

}  // namespace

void append_oriented_box(TriangleMesh& mesh, Vec3d center, Vec3d half_u, Vec3d half_v, Vec3d half_w,
                         Rgba8 color) {
  if (dot(cross(half_u, half_v), half_w) < 0) half_w = half_w * -1.0;
  const std::uint32_t base = next_index(mesh);
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3d p = center + half_u * ((corner & 1) ? 1.0 : -1.0) + half_v * ((corner & 2) ? 1.0 : -1.0) +
                    half_w * ((corner & 4) ? 1.0 : -1.0);
    push_vertex(mesh, p, color);
  }
  // Quads counter-clockwise seen from outside: -u, +u, -v, +v, -w, +w.
  static constexpr std::uint32_t kQuads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                                 {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : kQuads) {
    push_triangle(mesh, base + q[0], base + q[1], base + q[2]);
    push_triangle(mesh, base + q[0], base + q[2], base + q[3]);
  }
}

void append_box(TriangleMesh& mesh, const Box3d& box, Rgba8 color) {
  const Vec3d h = box.extent() * 0.5;
  if (!(h.x > 0 && h.y > 0 && h.z > 0)) throw std::invalid_argument("box: every extent must be positive");
  append_oriented_box(mesh, box.center(), {h.x, 0, 0}, {0, h.y, 0}, {0, 0, h.z}, color);
}

PrimitiveSize lathe_size(std::span<const LatheSample> profile, int segments) {
  check_segments(segments, "lathe");
  if (profile.size() < 2) throw std::invalid_argument("lathe: profile needs at least 2 samples");
  PrimitiveSize size;
  const auto seg = static_cast<std::uint64_t>(segments);
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const bool pole = profile[k].radius == 0;
    const bool end = k == 0 || k + 1 == profile.size();
    if (!(profile[k].radius >= 0) || (pole && !end))
      throw std::invalid_argument("lathe: sample " + std::to_string(k) + " has radius " +
                                  std::to_string(profile[k].radius) +
                                  " (only the first and last may be 0, none negative)");
    size.vertices += pole ? 1 : seg;
    if (k + 1 < profile.size()) {
      const LatheSample& next = profile[k + 1];
      if (next.radius == profile[k].radius && next.height == profile[k].height)
        throw std::invalid_argument("lathe: samples " + std::to_string(k) + " and " + std::to_string(k + 1) +
                                    " coincide");
      if (pole && next.radius == 0) throw std::invalid_argument("lathe: two consecutive poles");
      size.triangles += (pole || next.radius == 0) ? seg : 2 * seg;
    }
  }
  return size;
}

void append_lathe(TriangleMesh& mesh, Vec3d base, Vec3d axis, std::span<const LatheSample> profile,
                  int segments, Rgba8 color) {
  lathe_size(profile, segments);  // validates
  const Vec3d u = any_perpendicular(axis);
  const Vec3d v = cross(axis, u);
  const auto circle = circle_table(segments);
  const auto seg = static_cast<std::uint32_t>(segments);
  std::uint32_t previous = 0;
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const Vec3d center = base + axis * profile[k].height;
    const std::uint32_t first = next_index(mesh);
    if (profile[k].radius == 0) {
      push_vertex(mesh, center, color);
    } else {
      push_ring(mesh, center, u, v, profile[k].radius, circle, color);
    }
    if (k > 0) {
      if (profile[k - 1].radius == 0) {  // fan from the bottom pole
        for (std::uint32_t j = 0; j < seg; ++j)
          push_triangle(mesh, previous, first + (j + 1) % seg, first + j);
      } else if (profile[k].radius == 0) {  // fan to the top pole
        for (std::uint32_t j = 0; j < seg; ++j)
          push_triangle(mesh, previous + j, previous + (j + 1) % seg, first);
      } else {
        join_rings(mesh, previous, first, segments);
      }
    }
    previous = first;
  }
}

PrimitiveSize pipe_size(std::span<const Vec3d> path, const PipeStyle& style) {
  std::uint64_t rings = 0;
  plan_pipe(path, style, [&](const PipeRing&) { ++rings; });
  const auto seg = static_cast<std::uint64_t>(style.segments);
  const std::uint64_t caps = style.caps ? 1 : 0;
  return {2 * seg * (rings - 1) + caps * 2 * seg, rings * seg + caps * 2};
}

void append_pipe(TriangleMesh& mesh, std::span<const Vec3d> path, const PipeStyle& style, Rgba8 color) {
  const auto circle = circle_table(style.segments);
  const auto seg = static_cast<std::uint32_t>(style.segments);
  std::uint32_t first_ring = next_index(mesh);
  std::uint32_t previous = 0;
  bool have_previous = false;
  PipeRing first{}, last{};
  plan_pipe(path, style, [&](const PipeRing& r) {
    const std::uint32_t ring = next_index(mesh);
    push_ring(mesh, r.center, r.u, cross(r.tangent, r.u), style.radius, circle, color);
    if (have_previous) {
      join_rings(mesh, previous, ring, style.segments);
    } else {
      first_ring = ring;
      first = r;
    }
    previous = ring;
    have_previous = true;
    last = r;
  });
  if (style.caps) {
    const std::uint32_t start_center = next_index(mesh);
    push_vertex(mesh, first.center, color);
    for (std::uint32_t j = 0; j < seg; ++j)
      push_triangle(mesh, start_center, first_ring + (j + 1) % seg, first_ring + j);
    const std::uint32_t end_center = next_index(mesh);
    push_vertex(mesh, last.center, color);
    for (std::uint32_t j = 0; j < seg; ++j)
      push_triangle(mesh, end_center, previous + j, previous + (j + 1) % seg);
  }
}

}  // namespace cellbake
