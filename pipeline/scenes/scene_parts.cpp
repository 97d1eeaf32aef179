#include "pipeline/scenes/scene_parts.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pipeline/scenes/scene_math.h"

namespace cellbake {
namespace {

// Box from a corner-to-corner pair in any order.
Box3d span_box(Vec3d a, Vec3d b) {
  Box3d box;
  box.expand(a);
  box.expand(b);
  return box;
}

int coordinate_that_differs(Vec3d a, Vec3d b, const char* what) {
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (a[i] != b[i]) {
      if (axis >= 0)
        throw std::invalid_argument(std::string(what) + ": end points must differ in exactly one coordinate");
      axis = i;
    }
  }
  if (axis < 0) throw std::invalid_argument(std::string(what) + ": end points coincide");
  return axis;
}

}  // namespace

void add_wall(SceneBuilder& out, Vec3d start, bool along_x, double length, double height, double thickness,
              const std::vector<WallOpening>& openings, Rgba8 color) {
  // Cut the wall into vertical strips at every opening edge; inside a strip the
  // openings covering it leave solid intervals in z.
  std::vector<double> cuts{0.0, length};
  for (const WallOpening& o : openings) {
    if (!(o.from > 0 && o.to < length && o.from < o.to && o.bottom >= 0 && o.top < height &&
          o.bottom < o.top))
      throw std::invalid_argument("wall: opening outside the wall or empty");
    cuts.push_back(o.from);
    cuts.push_back(o.to);
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  auto emit = [&](double a, double b, double z0, double z1) {
    const Vec3d lo =
        along_x ? Vec3d{start.x + a, start.y, start.z + z0} : Vec3d{start.x, start.y + a, start.z + z0};
    const Vec3d hi = along_x ? Vec3d{start.x + b, start.y + thickness, start.z + z1}
                             : Vec3d{start.x + thickness, start.y + b, start.z + z1};
    out.box(span_box(lo, hi), color);
  };
  // Solid z-intervals that continue unchanged into the next strip are merged
  // into one box, so abutting boxes never share an identical face.
  struct Solid {
    double start, z0, z1;
  };
  std::vector<Solid> open;
  for (std::size_t s = 0; s + 1 < cuts.size(); ++s) {
    const double a = cuts[s], b = cuts[s + 1];
    std::vector<const WallOpening*> holes;
    for (const WallOpening& o : openings)
      if (o.from <= a && o.to >= b) holes.push_back(&o);
    std::sort(holes.begin(), holes.end(),
              [](const WallOpening* x, const WallOpening* y) { return x->bottom < y->bottom; });
    std::vector<Solid> here;
    double z = 0;
    for (const WallOpening* h : holes) {
      if (h->bottom > z) here.push_back({a, z, h->bottom});
      z = h->top;
    }
    if (height > z) here.push_back({a, z, height});
    std::vector<Solid> next;
    for (Solid& solid : here) {
      auto same = std::find_if(open.begin(), open.end(),
                               [&](const Solid& o) { return o.z0 == solid.z0 && o.z1 == solid.z1; });
      if (same != open.end()) solid.start = same->start;
      next.push_back(solid);
    }
    for (const Solid& o : open)
      if (std::none_of(next.begin(), next.end(),
                       [&](const Solid& n) { return n.start == o.start && n.z0 == o.z0 && n.z1 == o.z1; }))
        emit(o.start, a, o.z0, o.z1);
    open = std::move(next);
  }
  for (const Solid& o : open) emit(o.start, length, o.z0, o.z1);
}

void add_i_beam(SceneBuilder& out, Vec3d a, Vec3d b, double depth, double width, Rgba8 color) {
  const int axis = coordinate_that_differs(a, b, "i-beam");
  const double flange = std::max(0.01, depth * 0.08);
  const double web = std::max(0.008, width * 0.08);
  const Vec3d lo{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
  const Vec3d hi{std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
  // "Depth" direction: z for horizontal beams, x for columns; "width" the remaining one.
  const int depth_axis = axis == 2 ? 0 : 2;
  const int width_axis = 3 - axis - depth_axis;
  auto part = [&](double d0, double d1, double w0, double w1) {
    Vec3d p = lo, q = hi;
    p[depth_axis] = lo[depth_axis] + d0;
    q[depth_axis] = lo[depth_axis] + d1;
    p[width_axis] = lo[width_axis] + w0;
    q[width_axis] = lo[width_axis] + w1;
    out.box(span_box(p, q), color);
  };
  const double h = depth * 0.5, w = width * 0.5;
  part(-h, -h + flange, -w, w);
  part(h - flange, h, -w, w);
  part(-h + flange, h - flange, -web * 0.5, web * 0.5);
}

void add_grating(SceneBuilder& out, const Box3d& area, double pitch, Rgba8 color) {
  const Vec3d e = area.extent();
  const bool long_x = e.x >= e.y;
  const double length = long_x ? e.x : e.y;
  const double z = area.lo.z;
  const double bar_height = 0.03, frame = 0.06, bar = 0.008;
  // Edge frame: two long side members and two end members.
  if (long_x) {
    out.box({{area.lo.x, area.lo.y, z - 0.12}, {area.hi.x, area.lo.y + frame, z}}, color);
    out.box({{area.lo.x, area.hi.y - frame, z - 0.12}, {area.hi.x, area.hi.y, z}}, color);
  } else {
    out.box({{area.lo.x, area.lo.y, z - 0.12}, {area.lo.x + frame, area.hi.y, z}}, color);
    out.box({{area.hi.x - frame, area.lo.y, z - 0.12}, {area.hi.x, area.hi.y, z}}, color);
  }
  const int bars = std::max(2, static_cast<int>(std::floor(length / pitch)));
  const double step = length / bars;
  for (int i = 0; i <= bars; ++i) {
    const double c = (long_x ? area.lo.x : area.lo.y) + std::clamp(i * step, bar * 0.5, length - bar * 0.5);
    if (long_x)
      out.box({{c - bar * 0.5, area.lo.y + frame, z - bar_height}, {c + bar * 0.5, area.hi.y - frame, z}},
              color);
    else
      out.box({{area.lo.x + frame, c - bar * 0.5, z - bar_height}, {area.hi.x - frame, c + bar * 0.5, z}},
              color);
  }
  // Two tie bars along the long side, just under the bearing bars.
  for (int k = 1; k <= 2; ++k) {
    const double t = k / 3.0;
    if (long_x) {
      const double y = area.lo.y + e.y * t;
      out.box({{area.lo.x, y - bar, z - bar_height - 0.01}, {area.hi.x, y + bar, z - bar_height}}, color);
    } else {
      const double x = area.lo.x + e.x * t;
      out.box({{x - bar, area.lo.y, z - bar_height - 0.01}, {x + bar, area.hi.y, z - bar_height}}, color);
    }
  }
}

void add_railing(SceneBuilder& out, Vec3d a, Vec3d b, double height, bool end_posts, SceneTessellation& tess,
                 Rgba8 color) {
  coordinate_that_differs(a, b, "railing");
  const double len = length(b - a);
  const Vec3d dir = (b - a) * (1.0 / len);
  const int posts = std::max(1, static_cast<int>(std::ceil(len / 1.5)));
  for (int i = end_posts ? 0 : 1; i <= (end_posts ? posts : posts - 1); ++i) {
    const Vec3d p = a + dir * (len * i / posts);
    out.box({{p.x - 0.025, p.y - 0.025, p.z}, {p.x + 0.025, p.y + 0.025, p.z + height}}, color);
  }
  PipeStyle rail;
  rail.radius = 0.022;
  rail.segments = tess.circle_segments(rail.radius, 4);
  for (double h : {height * 0.5, height + 0.02}) {
    const Vec3d path[2] = {a + Vec3d{0, 0, h}, b + Vec3d{0, 0, h}};
    out.pipe(path, rail, color);
  }
}

void add_stairs(SceneBuilder& out, Vec3d foot, Vec3d run_direction, double width, double rise,
                SceneTessellation& tess, Rgba8 color) {
  const int steps = std::max(2, static_cast<int>(std::ceil(rise / 0.19)));
  const double step_rise = rise / steps, step_run = 0.26;
  const Vec3d side = normalized(cross(Vec3d{0, 0, 1}, run_direction));
  const Vec3d up{0, 0, 1};
  for (int i = 0; i < steps; ++i) {
    const Vec3d center = foot + run_direction * (step_run * (i + 0.5)) + up * (step_rise * (i + 1) - 0.025);
    out.oriented_box(center, run_direction * (step_run * 0.5 + 0.01), side * (width * 0.5), up * 0.025,
                     color);
  }
  // Stringers: slanted plates along both sides, from the foot to the top landing.
  const double run = step_run * steps;
  const Vec3d slope = normalized(run_direction * run + up * rise);
  const Vec3d slope_normal = normalized(cross(side, slope));
  const double slope_length = std::sqrt(run * run + rise * rise);
  for (double s : {-1.0, 1.0}) {
    const Vec3d center =
        foot + run_direction * (run * 0.5) + up * (rise * 0.5) + side * (s * (width * 0.5 + 0.03));
    out.oriented_box(center, slope * (slope_length * 0.5), side * 0.02, slope_normal * 0.12, color);
  }
  // Handrails: straight slanted tubes above the stringers.
  PipeStyle rail;
  rail.radius = 0.022;
  rail.segments = tess.circle_segments(rail.radius, 4);
  for (double s : {-1.0, 1.0}) {
    const Vec3d offset = side * (s * (width * 0.5 + 0.03)) + up * 0.95;
    const Vec3d path[2] = {foot + offset, foot + run_direction * run + up * rise + offset};
    out.pipe(path, rail, color);
  }
}

}  // namespace cellbake
