// Layout of the plant scene (see scene_plant.h). Reference: D. Wilson, "Spatially
// Encoded Image-Space Simplifications for Interactive Walkthrough", PhD thesis,
// UNC 2002, ch. 7 (the power plant test model).
#include "pipeline/scenes/scene_plant.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "pipeline/scenes/scene_math.h"
#include "pipeline/scenes/scene_parts.h"
#include "pipeline/scenes/scene_random.h"

namespace cellbake {
namespace {

constexpr double kHallX = 60, kHallY = 40, kHallZ = 30, kWall = 0.4;
constexpr double kLevels[3] = {8, 16, 24};
const Box3d kFurnace{{22, 14, 0.5}, {38, 26, 27.5}};

struct Palette {
  Rgba8 wall{196, 186, 166, 255}, roof{120, 120, 125, 255}, slab{150, 148, 140, 255}, frame{70, 90, 140, 255};
  Rgba8 window{90, 90, 95, 255}, grating{110, 110, 105, 255}, railing{230, 190, 30, 255},
      stairs{200, 170, 40, 255};
  Rgba8 waterwall{150, 70, 45, 255}, header{90, 90, 95, 255}, buckstay{40, 40, 45, 255},
      platen{180, 100, 50, 255};
  Rgba8 economizer{160, 120, 70, 255}, tank{215, 215, 205, 255}, machine{60, 120, 90, 255},
      motor{40, 60, 140, 255};
  Rgba8 services[6] = {{60, 140, 70, 255},   {50, 90, 170, 255},  {170, 50, 40, 255},
                       {220, 220, 215, 255}, {220, 120, 30, 255}, {130, 130, 130, 255}};
};

// Object counts and bar pitch derived from the scene density; all grow
// monotonically. (sqrt rather than pow: sqrt is exactly rounded everywhere.)
struct PlantDensity {
  int platens, economizer_banks, pipe_runs, machines;
  double grating_pitch;
  explicit PlantDensity(const SceneDensity& density) {
    const double g = std::sqrt(std::sqrt(density.structure));
    const double t = std::sqrt(std::sqrt(density.tessellation));
    platens = static_cast<int>(std::clamp(std::floor(5 * g), 4.0, 40.0));
    economizer_banks = static_cast<int>(std::clamp(std::floor(6 * g), 4.0, 48.0));
    pipe_runs = static_cast<int>(std::clamp(std::floor(10 * g), 8.0, 160.0));
    machines = static_cast<int>(std::clamp(std::floor(10 * g), 10.0, 32.0));
    grating_pitch = std::clamp(0.3 / t, 0.03, 0.3);
  }
};

void hall_shell(SceneBuilder& out, SceneRng& rng, const Palette& c) {
  out.box({{-0.5, -0.5, -0.3}, {kHallX + 0.5, kHallY + 0.5, 0}}, c.slab);
  out.box({{0, 0, kHallZ}, {kHallX, kHallY, kHallZ + 0.4}}, c.roof);
  const double bands[3][2] = {{3.5, 6.5}, {12, 15}, {20.5, 24.5}};
  auto window_frames = [&](bool along_x, double across, const WallOpening& o) {
    const double mid = (o.from + o.to) * 0.5, mz = (o.bottom + o.top) * 0.5, t = 0.04;
    if (along_x) {
      out.box({{mid - t, across, o.bottom}, {mid + t, across + 0.12, o.top}}, c.window);
      out.box({{o.from, across, mz - t}, {o.to, across + 0.12, mz + t}}, c.window);
    } else {
      out.box({{across, mid - t, o.bottom}, {across + 0.12, mid + t, o.top}}, c.window);
      out.box({{across, o.from, mz - t}, {across + 0.12, o.to, mz + t}}, c.window);
    }
  };
  for (int side = 0; side < 2; ++side) {  // long walls along x at y = 0 and y = 40 - wall
    std::vector<WallOpening> openings;
    for (int b = 0; b < 3; ++b)
      for (int k = 0; k < 10; ++k) {
        if (side == 0 && b == 0 && (k == 4 || k == 5)) continue;  // the gate is there
        openings.push_back({1.5 + 6 * k, 4.5 + 6 * k, bands[b][0], bands[b][1]});
      }
    if (side == 0) openings.push_back({27, 33, 0, 7});
    const double y = side == 0 ? 0 : kHallY - kWall;
    add_wall(out, {0, y, 0}, true, kHallX, kHallZ, kWall, openings, rng.vary(c.wall, 6));
    for (const WallOpening& o : openings)
      if (o.bottom > 0) window_frames(true, y + 0.14, o);
  }
  for (int side = 0; side < 2; ++side) {  // end walls along y at x = 0 and x = 60 - wall
    std::vector<WallOpening> openings;
    for (int b = 0; b < 3; ++b)
      for (int k = 0; k < 6; ++k)
        openings.push_back({2.5 + 6.5 * k, 5.0 + 6.5 * k, bands[b][0], bands[b][1]});
    openings.push_back({18.5, 21.5, 0, 3.5});
    const double x = side == 0 ? 0 : kHallX - kWall;
    std::vector<WallOpening> local = openings;  // the end walls start after the long walls, at y = kWall
    for (WallOpening& o : local) {
      o.from -= kWall;
      o.to -= kWall;
    }
    add_wall(out, {x, kWall, 0}, false, kHallY - 2 * kWall, kHallZ, kWall, local, rng.vary(c.wall, 6));
    for (const WallOpening& o : openings)
      if (o.bottom > 0) window_frames(false, x + 0.14, o);
  }
}

void steel_frame(SceneBuilder& out, SceneRng& rng, const Palette& c) {
  const Rgba8 steel = rng.vary(c.frame, 8);
  for (int k = 0; k < 10; ++k) {
    const double x = 3 + 6 * k;
    for (double y : {0.75, kHallY - 0.75}) add_i_beam(out, {x, y, 0}, {x, y, kHallZ}, 0.4, 0.3, steel);
    add_i_beam(out, {x, 0.75, 29.5}, {x, kHallY - 0.75, 29.5}, 0.9, 0.3, steel);  // roof girders
  }
  for (double level : {8.0, 16.0, 24.0, 29.0})
    for (double y : {0.75, kHallY - 0.75})
      add_i_beam(out, {0.4, y, level - 0.45}, {kHallX - 0.4, y, level - 0.45}, 0.5, 0.25, steel);
  // Mezzanine supports: the west bay (x < 16.5) at levels 8 and 16, the east bay (x > 43.5) at 8.
  for (double y : {8.0, 16.0, 24.0, 32.0}) {
    add_i_beam(out, {16.3, y, 0}, {16.3, y, 16}, 0.35, 0.3, steel);
    add_i_beam(out, {43.7, y, 0}, {43.7, y, 8}, 0.35, 0.3, steel);
  }
  for (double x : {3.0, 9.0, 15.0})
    for (double level : {8.0, 16.0})
      add_i_beam(out, {x, 0.75, level - 0.5}, {x, kHallY - 0.75, level - 0.5}, 0.5, 0.25, steel);
  for (double x : {45.0, 51.0, 57.0})
    add_i_beam(out, {x, 0.75, 7.5}, {x, kHallY - 0.75, 7.5}, 0.5, 0.25, steel);
  // Columns at the corners of the walkway ring around the furnace.
  for (double x : {20.2, 39.8})
    for (double y : {12.2, 27.8}) add_i_beam(out, {x, y, 0}, {x, y, 24}, 0.3, 0.3, steel);
}

void floors_and_walkways(SceneBuilder& out, SceneRng& rng, const Palette& c, const PlantDensity& density,
                         SceneTessellation& tess) {
  for (double level : {8.0, 16.0})
    out.box({{kWall, kWall, level - 0.25}, {16.5, kHallY - kWall, level}}, rng.vary(c.slab, 5));
  out.box({{43.5, kWall, 7.75}, {kHallX - kWall, kHallY - kWall, 8}}, rng.vary(c.slab, 5));
  for (double level : kLevels) {
    const Box3d strips[4] = {{{20, 12, level}, {40, 13.5, level}},
                             {{20, 26.5, level}, {40, 28, level}},
                             {{20, 13.5, level}, {21.5, 26.5, level}},
                             {{38.5, 13.5, level}, {40, 26.5, level}}};
    for (const Box3d& s : strips) {
      Box3d area = s;
      area.hi.z = level + 0.01;  // walking surface; bars hang below
      area.lo.z = level;
      add_grating(out, area, density.grating_pitch, rng.vary(c.grating, 6));
    }
    const Rgba8 rail = rng.vary(c.railing, 8);
    add_railing(out, {20, 12, level}, {40, 12, level}, 1.1, true, tess, rail);
    add_railing(out, {20, 28, level}, {40, 28, level}, 1.1, true, tess, rail);
    add_railing(out, {20, 12, level}, {20, 28, level}, 1.1, false, tess, rail);
    add_railing(out, {40, 12, level}, {40, 28, level}, 1.1, false, tess, rail);
  }
  add_grating(out, {{40, 19, 8}, {43.5, 21, 8.01}}, density.grating_pitch,
              rng.vary(c.grating, 6));  // bridge east
}

void stair_tower(SceneBuilder& out, SceneRng& rng, const Palette& c, SceneTessellation& tess) {
  const Rgba8 color = rng.vary(c.stairs, 8);
  add_stairs(out, {17.7, 1.5, 0}, {0, 1, 0}, 1.2, 8, tess, color);
  out.box({{16.5, 12.7, 7.8}, {19.0, 14.2, 8}}, color);
  add_stairs(out, {17.7, 14.2, 8}, {0, 1, 0}, 1.2, 8, tess, color);
  out.box({{16.5, 25.4, 15.8}, {20.0, 26.9, 16}}, color);
  add_stairs(out, {19.2, 25.4, 16}, {0, -1, 0}, 1.2, 8, tess, color);
  out.box({{18.4, 12.7, 23.8}, {20.5, 14.2, 24}}, color);
}

// Waterwalls (vertical tubes on the furnace faces), their headers, buckstays,
// platens (serpentine tubes in x-z planes, upper furnace) and economizer banks
// (serpentines in y-z planes, lower furnace): the dense arrays of long thin pipes.
void furnace(SceneBuilder& out, SceneRng& rng, const Palette& c, const PlantDensity& density,
             SceneTessellation& tess) {
  const double pitch = 0.1;
  auto wall_tube = [&](double x, double y) {
    PipeStyle tube;
    tube.radius = 0.04;
    tube.segments = tess.circle_segments(tube.radius);
    tube.max_piece_length = tess.piece_length();
    tube.caps = false;
    const Vec3d path[2] = {{x, y, 1.3}, {x, y, 26.7}};
    out.pipe(path, tube, rng.vary(c.waterwall, 10));
  };
  const int along_x = static_cast<int>(std::round(kFurnace.extent().x / pitch));
  const int along_y = static_cast<int>(std::round(kFurnace.extent().y / pitch));
  for (int i = 0; i < along_x; ++i) {
    const double x = kFurnace.lo.x + pitch * (i + 0.5);
    wall_tube(x, kFurnace.lo.y);
    wall_tube(x, kFurnace.hi.y);
  }
  for (int i = 0; i < along_y; ++i) {
    const double y = kFurnace.lo.y + pitch * (i + 0.5);
    wall_tube(kFurnace.lo.x, y);
    wall_tube(kFurnace.hi.x, y);
  }
  PipeStyle header;
  header.radius = 0.2;
  header.segments = tess.circle_segments(header.radius, 8);
  for (double z : {1.1, 26.9}) {
    const double x0 = kFurnace.lo.x - 0.3, x1 = kFurnace.hi.x + 0.3, y0 = kFurnace.lo.y - 0.3,
                 y1 = kFurnace.hi.y + 0.3;
    const Vec3d headers[4][2] = {{{x0, kFurnace.lo.y, z}, {x1, kFurnace.lo.y, z}},
                                 {{x0, kFurnace.hi.y, z}, {x1, kFurnace.hi.y, z}},
                                 {{kFurnace.lo.x, y0, z}, {kFurnace.lo.x, y1, z}},
                                 {{kFurnace.hi.x, y0, z}, {kFurnace.hi.x, y1, z}}};
    for (const auto& h : headers) out.pipe(h, header, rng.vary(c.header, 6));
  }
  for (double z = 3; z < 26; z += 3) {
    const double lo_x = kFurnace.lo.x - 0.3, hi_x = kFurnace.hi.x + 0.3, lo_y = kFurnace.lo.y - 0.3,
                 hi_y = kFurnace.hi.y + 0.3;
    add_i_beam(out, {lo_x, lo_y, z}, {hi_x, lo_y, z}, 0.3, 0.12, c.buckstay);
    add_i_beam(out, {lo_x, hi_y, z}, {hi_x, hi_y, z}, 0.3, 0.12, c.buckstay);
    add_i_beam(out, {lo_x, lo_y + 0.1, z}, {lo_x, hi_y - 0.1, z}, 0.3, 0.12, c.buckstay);
    add_i_beam(out, {hi_x, lo_y + 0.1, z}, {hi_x, hi_y - 0.1, z}, 0.3, 0.12, c.buckstay);
  }

  // A serpentine: `runs` parallel legs along `run_axis` between a and b, stepping
  // down by `step` in z, with inlet and outlet risers to z_top.
  auto serpentine = [&](Vec3d run_axis, double a, double b, Vec3d plane_point, double z_first, int runs,
                        double step, double z_top, Rgba8 color) {
    std::vector<Vec3d> path;
    double last = a;
    auto at = [&](double s, double z) {
      Vec3d p = plane_point + run_axis * s;
      p.z = z;
      return p;
    };
    path.push_back(at(a, z_top));
    for (int r = 0; r < runs; ++r) {
      const double z = z_first - step * r;
      const bool forward = r % 2 == 0;
      const double from = forward ? a : b, to = forward ? b : a;
      const double overshoot = r + 1 == runs ? (forward ? 0.3 : -0.3) : 0.0;
      path.push_back(at(from, z));
      last = to + overshoot;
      path.push_back(at(last, z));
    }
    path.push_back(at(last, z_top));
    PipeStyle tube;
    tube.radius = 0.05;
    tube.bend_radius = 0.0675;
    tube.segments = tess.circle_segments(tube.radius);
    tube.bend_segments = tess.bend_segments(tube.bend_radius);
    tube.max_piece_length = tess.piece_length();
    tube.caps = false;
    out.pipe(path, tube, color);
  };
  for (int k = 0; k < density.platens; ++k) {
    const double y = kFurnace.lo.y + 0.6 + (kFurnace.extent().y - 1.2) * (k + 0.5) / density.platens;
    serpentine({1, 0, 0}, 0, 14, {23, y, 0}, 25, 50, 0.15, 26.9, rng.vary(c.platen, 10));
  }
  for (int k = 0; k < density.economizer_banks; ++k) {
    const double x = kFurnace.lo.x + 0.6 + (kFurnace.extent().x - 1.2) * (k + 0.5) / density.economizer_banks;
    serpentine({0, 1, 0}, 0, 10.8, {x, 14.6, 0}, 10, 47, 0.15, 11.5, rng.vary(c.economizer, 10));
  }
  // Downcomers: big pipes from the top of the furnace over the north walkway down to the floor.
  PipeStyle downcomer;
  downcomer.radius = 0.25;
  downcomer.bend_radius = 0.6;
  downcomer.segments = tess.circle_segments(downcomer.radius, 8);
  downcomer.bend_segments = tess.bend_segments(downcomer.bend_radius);
  downcomer.max_piece_length = tess.piece_length();
  for (double x : {24.0, 28.0, 32.0, 36.0}) {
    const Vec3d path[4] = {{x, 25.5, 27.2}, {x, 25.5, 28.6}, {x, 28.8, 28.6}, {x, 28.8, 0.3}};
    out.pipe(path, downcomer, rng.vary(c.header, 6));
  }
}

struct Nozzle {
  Vec3d top;  // where a pipe run starts, straight up from here
};

void tanks(SceneBuilder& out, SceneRng& rng, const Palette& c, SceneTessellation& tess,
           std::vector<Nozzle>& nozzles) {
  for (double y : {26.5, 33.5})
    for (double x : {4.5, 9.0, 13.5}) {
      const double r = rng.uniform(1.3, 1.9), h = rng.uniform(3.5, 4.8), legs = 0.5;
      const int segments = tess.circle_segments(r, 12);
      const int side_pieces = std::max(1, static_cast<int>(std::ceil(h / tess.piece_length())));
      const int dome = std::max(2, tess.bend_segments(r));
      std::vector<LatheSample> profile{{0, 0}, {r, 0}};
      for (int k = 1; k <= side_pieces; ++k) profile.push_back({r, h * k / side_pieces});
      for (int k = 1; k < dome; ++k) {
        const SinCos a = sin_cos_turns(0.25 * k / dome);
        profile.push_back({r * a.c, h + 0.4 * r * a.s});
      }
      profile.push_back({0, h + 0.4 * r});
      const Rgba8 color = rng.vary(c.tank, 8);
      out.lathe({x, y, legs}, {0, 0, 1}, profile, segments, color);
      for (double sx : {-0.6, 0.6})
        for (double sy : {-0.6, 0.6})
          out.box(
              {{x + sx * r - 0.1, y + sy * r - 0.1, 0}, {x + sx * r + 0.1, y + sy * r + 0.1, legs + 0.05}},
              c.frame);
      const double nozzle_r = 0.15;
      const LatheSample neck[4] = {{0, 0}, {nozzle_r, 0}, {nozzle_r, 0.35}, {0, 0.35}};
      const Vec3d nozzle_base{x + 0.5 * r, y, legs + h + 0.2 * r};
      out.lathe(nozzle_base, {0, 0, 1}, neck, tess.circle_segments(nozzle_r), color);
      nozzles.push_back({nozzle_base + Vec3d{0, 0, 0.35}});
    }
}

void machinery(SceneBuilder& out, SceneRng& rng, const Palette& c, const PlantDensity& density,
               SceneTessellation& tess, std::vector<Nozzle>& nozzles) {
  std::vector<Vec3d> slots;
  for (int row = 0; row < 6; ++row)
    for (int col = 0; col < 4; ++col) slots.push_back({45.5 + 3.8 * col, 8.5 + 4.2 * row, 0});
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) slots.push_back({3.5 + 4.5 * col, 9.0 + 4.0 * row, 0});
  const int count = std::min<int>(density.machines, static_cast<int>(slots.size()));
  for (int m = 0; m < count; ++m) {
    const Vec3d p = slots[static_cast<std::size_t>(m)];
    const double len = rng.uniform(2.0, 2.8), wid = rng.uniform(1.2, 1.6);
    out.box({{p.x - len / 2, p.y - wid / 2, 0}, {p.x + len / 2, p.y + wid / 2, 0.3}}, rng.vary(c.frame, 10));
    // Motor: a horizontal cylinder with end bells, along x.
    const double mr = rng.uniform(0.3, 0.45), ml = len * 0.45;
    const LatheSample motor[6] = {{0, 0}, {mr * 0.8, 0}, {mr, 0.1}, {mr, ml - 0.1}, {mr * 0.8, ml}, {0, ml}};
    out.lathe({p.x - len / 2 + 0.1, p.y, 0.3 + mr + 0.05}, {1, 0, 0}, motor, tess.circle_segments(mr, 8),
              rng.vary(c.motor, 12));
    // Pump casing: a vertical drum with a flange and the outlet nozzle on top.
    const double pr = rng.uniform(0.3, 0.4), ph = rng.uniform(0.9, 1.4);
    const LatheSample pump[8] = {{0, 0},
                                 {pr, 0},
                                 {pr, ph},
                                 {pr * 1.2, ph},
                                 {pr * 1.2, ph + 0.08},
                                 {pr * 0.4, ph + 0.08},
                                 {pr * 0.4, ph + 0.4},
                                 {0, ph + 0.4}};
    const Vec3d pump_base{p.x + len / 2 - pr - 0.1, p.y, 0.3};
    out.lathe(pump_base, {0, 0, 1}, pump, tess.circle_segments(pr, 8), rng.vary(c.machine, 12));
    out.box({{p.x - 0.2, p.y + wid / 2 - 0.3, 0.3}, {p.x + 0.3, p.y + wid / 2, 1.3}},
            rng.vary(c.machine, 20));  // control box
    nozzles.push_back({pump_base + Vec3d{0, 0, ph + 0.4}});
  }
}

// Pipe racks along both long walls and the runs between nozzles that use them,
// plus long header lines lying in the racks.
void pipe_racks(SceneBuilder& out, SceneRng& rng, const Palette& c, const PlantDensity& density,
                SceneTessellation& tess, const std::vector<Nozzle>& nozzles) {
  const double rack_y[2] = {3.0, 37.0};
  for (double y0 : rack_y) {
    for (int k = 0; k < 10; ++k) {
      const double x = 3 + 6 * k + 1.0;
      for (double dy : {-0.9, 0.9}) add_i_beam(out, {x, y0 + dy, 0}, {x, y0 + dy, 6.1}, 0.25, 0.2, c.frame);
      add_i_beam(out, {x, y0 - 1.0, 6.0}, {x, y0 + 1.0, 6.0}, 0.2, 0.15, c.frame);
    }
    for (int line = 0; line < 6; ++line) {
      PipeStyle style;
      style.radius = 0.08 + 0.02 * line;
      style.segments = tess.circle_segments(style.radius, 8);
      style.max_piece_length = tess.piece_length();
      const double y = y0 - 0.75 + 0.3 * line;
      const Vec3d path[2] = {{1.0, y, 6.1 + style.radius}, {59.0, y, 6.1 + style.radius}};
      out.pipe(path, style, c.services[rng.below(6)]);
    }
  }
  if (nozzles.size() < 2) return;
  for (int run = 0; run < density.pipe_runs; ++run) {
    const Nozzle& a = nozzles[rng.below(static_cast<std::uint32_t>(nozzles.size()))];
    const Nozzle& b = nozzles[rng.below(static_cast<std::uint32_t>(nozzles.size()))];
    const double rack = rack_y[rng.below(2)];
    const double y_run = rack - 0.9 + 1.8 * rng.unit();
    const double z_run = 6.5 + 0.3 * (run % 4);
    PipeStyle style;
    style.radius = rng.uniform(0.03, 0.12);
    style.bend_radius = 2.0 * style.radius;
    style.segments = tess.circle_segments(style.radius);
    style.bend_segments = tess.bend_segments(style.bend_radius);
    style.max_piece_length = tess.piece_length();
    double xb = b.top.x;
    if (std::fabs(xb - a.top.x) < 0.8) xb = a.top.x + (a.top.x < 30 ? 1.2 : -1.2);
    const double yb = std::fabs(b.top.y - y_run) < 0.8 ? b.top.y + 1.0 : b.top.y;
    const double zb = std::min(b.top.z, z_run - 0.8);
    const Vec3d path[6] = {
        a.top,       {a.top.x, a.top.y, z_run}, {a.top.x, y_run, z_run}, {xb, y_run, z_run}, {xb, yb, z_run},
        {xb, yb, zb}};
    out.pipe(path, style, rng.vary(c.services[rng.below(6)], 10));
  }
}

}  // namespace

void build_plant_scene(const SceneDensity& scene_density, std::uint64_t seed, SceneBuilder& out) {
  const PlantDensity density(scene_density);
  SceneRng rng(seed);
  SceneTessellation tess(0.02 / scene_density.tessellation, 40.0 / scene_density.tessellation, seed);
  const Palette colors;
  hall_shell(out, rng, colors);
  steel_frame(out, rng, colors);
  floors_and_walkways(out, rng, colors, density, tess);
  stair_tower(out, rng, colors, tess);
  furnace(out, rng, colors, density, tess);
  std::vector<Nozzle> nozzles;
  tanks(out, rng, colors, tess, nozzles);
  machinery(out, rng, colors, density, tess, nozzles);
  pipe_racks(out, rng, colors, density, tess, nozzles);
}

}  // namespace cellbake
