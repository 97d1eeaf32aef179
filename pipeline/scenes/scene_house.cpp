// Layout of the house scene (see scene_house.h). Reference: D. Wilson,
// "Spatially Encoded Image-Space Simplifications for Interactive Walkthrough",
// PhD thesis, UNC 2002 (the house test environment, Fig. 1.1).
#include "pipeline/scenes/scene_house.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "pipeline/scenes/scene_math.h"
#include "pipeline/scenes/scene_parts.h"
#include "pipeline/scenes/scene_random.h"

namespace cellbake {
namespace {

constexpr double kRoomX = 4.5, kRoomY = 4.0, kStorey = 3.0, kSlab = 0.2, kOuter = 0.25, kInner = 0.12;

struct Palette {
  Rgba8 outer{232, 222, 196, 255}, slab{185, 180, 170, 255}, floor{160, 112, 72, 255}, wood{135, 88, 52, 255};
  Rgba8 metal{55, 55, 60, 255}, stairs{150, 100, 60, 255}, frame{245, 245, 240, 255};
  Rgba8 tints[5] = {{238, 232, 214, 255},
                    {214, 228, 236, 255},
                    {236, 214, 210, 255},
                    {220, 236, 214, 255},
                    {240, 240, 232, 255}};
  Rgba8 fabrics[5] = {
      {150, 40, 40, 255}, {40, 70, 130, 255}, {70, 110, 60, 255}, {200, 170, 90, 255}, {110, 80, 120, 255}};
};

struct HouseDensity {
  int rooms_x, rooms_y, floors;
  explicit HouseDensity(const SceneDensity& density) {
    const double g = std::sqrt(std::sqrt(density.structure));
    rooms_x = static_cast<int>(std::clamp(std::floor(2.0 * g), 2.0, 60.0));
    rooms_y = static_cast<int>(std::clamp(std::floor(1.6 * g), 2.0, 60.0));
    floors = static_cast<int>(std::clamp(std::floor(1.5 * g), 2.0, 40.0));
  }
};

class Furnisher {
 public:
  Furnisher(SceneBuilder& out, SceneRng& rng, SceneTessellation& tess, const Palette& c)
      : out_(out), rng_(rng), tess_(tess), c_(c) {}

  // A vertical turned cylinder (leg, post) with closed ends.
  void post(Vec3d base, double radius, double height, Rgba8 color) {
    const LatheSample profile[4] = {{0, 0}, {radius, 0}, {radius, height}, {0, height}};
    out_.lathe(base, {0, 0, 1}, profile, tess_.circle_segments(radius, 5), color);
  }

  void table(Vec3d center, double w, double d, Rgba8 wood) {
    const double h = 0.74;
    out_.box({{center.x - w / 2, center.y - d / 2, center.z + h - 0.04},
              {center.x + w / 2, center.y + d / 2, center.z + h}},
             wood);
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        post({center.x + sx * (w / 2 - 0.06), center.y + sy * (d / 2 - 0.06), center.z}, 0.025, h - 0.04,
             wood);
  }

  // A chair whose back is on the side `back` (unit x or y vector) of its seat.
  void chair(Vec3d center, Vec3d back, Rgba8 wood, Rgba8 fabric) {
    const double s = 0.22, seat = 0.45;
    out_.box(
        {{center.x - s, center.y - s, center.z + seat - 0.05}, {center.x + s, center.y + s, center.z + seat}},
        fabric);
    const Vec3d b = center + back * (s - 0.02);
    const Vec3d across{std::fabs(back.y), std::fabs(back.x), 0};
    out_.box({{b.x - 0.02 - across.x * s, b.y - 0.02 - across.y * s, center.z + seat},
              {b.x + 0.02 + across.x * s, b.y + 0.02 + across.y * s, center.z + 0.95}},
             wood);
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        post({center.x + sx * (s - 0.03), center.y + sy * (s - 0.03), center.z}, 0.016, seat - 0.05, wood);
  }

  // A cupboard against a wall; `front` points into the room.
  void cupboard(Vec3d center, Vec3d front, double w, double h, Rgba8 wood) {
    const Vec3d across{std::fabs(front.y), std::fabs(front.x), 0};
    const double d = 0.5;
    out_.oriented_box(center + Vec3d{0, 0, h / 2}, across * (w / 2), front * (d / 2), {0, 0, h / 2}, wood);
    for (double side : {-1.0, 1.0}) {
      const Vec3d door =
          center + front * (d / 2 + 0.01) + across * (side * w / 4) + Vec3d{0, 0, h / 2 + 0.02};
      out_.oriented_box(door, across * (w / 4 - 0.01), front * 0.01, {0, 0, h / 2 - 0.05},
                        rng_.vary(wood, 8));
      const LatheSample knob[4] = {{0, 0}, {0.012, 0}, {0.02, 0.04}, {0, 0.045}};
      out_.lathe(door + front * 0.01 - across * (side * (w / 4 - 0.06)), front, knob,
                 tess_.circle_segments(0.02, 4), c_.metal);
    }
  }

  void bed(Vec3d corner, bool along_x, Rgba8 wood, Rgba8 fabric) {
    const double l = 2.05, w = 1.45;
    const double lx = along_x ? l : w, ly = along_x ? w : l;
    out_.box({{corner.x, corner.y, corner.z}, {corner.x + lx, corner.y + ly, corner.z + 0.3}}, wood);
    out_.box({{corner.x + 0.03, corner.y + 0.03, corner.z + 0.3},
              {corner.x + lx - 0.03, corner.y + ly - 0.03, corner.z + 0.5}},
             fabric);
    if (along_x) {
      out_.box({{corner.x, corner.y, corner.z + 0.3}, {corner.x + 0.06, corner.y + ly, corner.z + 1.0}},
               wood);
      out_.box({{corner.x + 0.1, corner.y + 0.15, corner.z + 0.5},
                {corner.x + 0.45, corner.y + ly - 0.15, corner.z + 0.62}},
               c_.frame);
    } else {
      out_.box({{corner.x, corner.y, corner.z + 0.3}, {corner.x + lx, corner.y + 0.06, corner.z + 1.0}},
               wood);
      out_.box({{corner.x + 0.15, corner.y + 0.1, corner.z + 0.5},
                {corner.x + lx - 0.15, corner.y + 0.45, corner.z + 0.62}},
               c_.frame);
    }
  }

  void sofa(Vec3d corner, Rgba8 fabric) {  // along x, back on the -y side
    const double l = 2.1, d = 0.9;
    out_.box({{corner.x, corner.y, corner.z}, {corner.x + l, corner.y + d, corner.z + 0.42}}, fabric);
    out_.box({{corner.x, corner.y, corner.z + 0.42}, {corner.x + l, corner.y + 0.22, corner.z + 0.85}},
             fabric);
    for (double x : {corner.x, corner.x + l - 0.18})
      out_.box({{x, corner.y + 0.22, corner.z + 0.42}, {x + 0.18, corner.y + d, corner.z + 0.65}},
               rng_.vary(fabric, 10));
    for (int k = 0; k < 3; ++k) {
      const double x0 = corner.x + 0.2 + k * 0.57;
      out_.box({{x0, corner.y + 0.25, corner.z + 0.42}, {x0 + 0.55, corner.y + d - 0.02, corner.z + 0.52}},
               rng_.vary(fabric, 12));
    }
  }

  // A standing lamp: weighted base, stem and a conical shade closed on top.
  void lamp(Vec3d base, Rgba8 shade) {
    const int rings = std::max(1, tess_.bend_segments(0.2));
    std::vector<LatheSample> profile{{0, 0},        {0.16, 0},    {0.16, 0.03},
                                     {0.014, 0.05}, {0.014, 1.3}, {0.22, 1.3}};
    for (int k = 1; k <= rings; ++k) {
      const double t = static_cast<double>(k) / rings;
      profile.push_back({0.22 - 0.1 * t, 1.3 + 0.3 * t});
    }
    profile.push_back({0, 1.6});
    out_.lathe(base, {0, 0, 1}, profile, tess_.circle_segments(0.22, 6), shade);
  }

  // A vase: a smooth bulb profile.
  void vase(Vec3d base, double height, Rgba8 color) {
    const int rings = std::max(3, tess_.circle_segments(height, 6) / 2);
    std::vector<LatheSample> profile{{0, 0}};
    for (int k = 0; k <= rings; ++k) {
      const double t = static_cast<double>(k) / rings;
      const SinCos bulge = sin_cos_turns(0.5 * t);
      profile.push_back({height * (0.12 + 0.22 * bulge.s + 0.06 * t), height * t});
    }
    profile.push_back({0, height});
    out_.lathe(base, {0, 0, 1}, profile, tess_.circle_segments(0.3 * height, 6), color);
  }

  // Thin vertical bars across an opening in a wall along x (`along_x`) or y,
  // centred in the wall thickness at `across`, with two horizontal tie bars.
  void grille(double across, bool along_x, double from, double to, double bottom, double top) {
    PipeStyle bar;
    bar.radius = 0.008;
    bar.segments = tess_.circle_segments(bar.radius, 4);
    auto at = [&](double s, double z) { return along_x ? Vec3d{s, across, z} : Vec3d{across, s, z}; };
    const int bars = std::max(2, static_cast<int>(std::floor((to - from) / 0.11)));
    for (int i = 1; i < bars; ++i) {
      const double s = from + (to - from) * i / bars;
      const Vec3d path[2] = {at(s, bottom + 0.01), at(s, top - 0.01)};
      out_.pipe(path, bar, c_.metal);
    }
    for (double z : {bottom + 0.1, top - 0.1}) {
      const Vec3d path[2] = {at(from + 0.01, z), at(to - 0.01, z)};
      out_.pipe(path, bar, c_.metal);
    }
  }

 private:
  SceneBuilder& out_;
  SceneRng& rng_;
  SceneTessellation& tess_;
  const Palette& c_;
};

// Room interior [x0, x1] x [y0, y1] at floor height z: one of four layouts.
void furnish_room(Furnisher& f, SceneRng& rng, const Palette& c, double x0, double y0, double x1, double y1,
                  double z) {
  const Rgba8 wood = rng.vary(c.wood, 14);
  const Rgba8 fabric = rng.vary(c.fabrics[rng.below(5)], 14);
  const double cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
  switch (rng.below(4)) {
    case 0: {  // dining
      f.table({cx, cy, z}, 1.6, 0.9, wood);
      for (double sx : {-0.45, 0.45}) {
        f.chair({cx + sx, cy - 0.7, z}, {0, -1, 0}, wood, fabric);
        f.chair({cx + sx, cy + 0.7, z}, {0, 1, 0}, wood, fabric);
      }
      f.vase({cx, cy, z + 0.74}, 0.3, rng.vary(c.fabrics[rng.below(5)], 20));
      f.cupboard({x0 + 0.8, y1 - 0.3, z}, {0, -1, 0}, 1.2, 1.9, wood);
      break;
    }
    case 1: {  // bedroom
      f.bed({x0 + 0.1, y0 + 0.3, z}, true, wood, fabric);
      f.cupboard({x1 - 0.9, y1 - 0.3, z}, {0, -1, 0}, 1.4, 2.1, wood);
      f.table({x1 - 0.5, y0 + 0.5, z}, 0.5, 0.5, wood);
      f.lamp({x0 + 0.4, y1 - 0.5, z}, rng.vary(c.frame, 10));
      break;
    }
    case 2: {  // living room
      f.sofa({cx - 1.05, y0 + 0.15, z}, fabric);
      f.table({cx, cy + 0.2, z}, 1.0, 0.55, wood);
      f.vase({cx + 0.2, cy + 0.2, z + 0.74}, 0.25, rng.vary(c.fabrics[rng.below(5)], 20));
      f.lamp({x1 - 0.4, y0 + 0.4, z}, rng.vary(c.fabrics[3], 10));
      f.cupboard({cx, y1 - 0.3, z}, {0, -1, 0}, 2.0, 1.2, wood);
      break;
    }
    default: {  // kitchen: counters along two walls, a small table with two chairs
      for (double x = x0 + 0.05; x + 0.6 <= x1 - 0.05; x += 0.6) {
        f.cupboard({x + 0.3, y1 - 0.3, z}, {0, -1, 0}, 0.58, 0.88, rng.vary(c.frame, 6));
      }
      f.table({cx, cy - 0.4, z}, 0.9, 0.7, wood);
      f.chair({cx - 0.35, cy - 1.1, z}, {0, -1, 0}, wood, fabric);
      f.chair({cx + 0.35, cy - 1.1, z}, {0, -1, 0}, wood, fabric);
      break;
    }
  }
}

}  // namespace

void build_house_scene(const SceneDensity& scene_density, std::uint64_t seed, SceneBuilder& out) {
  const HouseDensity density(scene_density);
  SceneRng rng(seed);
  SceneTessellation tess(0.004 / scene_density.tessellation, 0, seed);
  const Palette c;
  Furnisher furnish(out, rng, tess, c);
  const double size_x = density.rooms_x * kRoomX, size_y = density.rooms_y * kRoomY;
  const double well_x = kRoomX - 0.05, well_y = size_y - kOuter - 1.1;  // stairwell in room (0, last row)

  out.box({{-2, -2, -kSlab - 0.3}, {size_x + 2, size_y + 2, -kSlab}}, rng.vary(c.slab, 6));  // ground plate
  for (int f = 0; f <= density.floors; ++f) {
    const double z = f * kStorey;
    const Rgba8 slab = rng.vary(c.slab, 6);
    if (f == 0 || f == density.floors) {
      out.box({{0, 0, z - kSlab}, {size_x, size_y, z}}, slab);
    } else {  // leave the stairwell open
      out.box({{0, 0, z - kSlab}, {size_x, well_y, z}}, slab);
      out.box({{well_x, well_y, z - kSlab}, {size_x, size_y, z}}, slab);
      out.box({{0, well_y, z - kSlab}, {kOuter, size_y, z}}, slab);
      out.box({{kOuter, size_y - kOuter, z - kSlab}, {well_x, size_y, z}}, slab);
    }
    if (f == density.floors) break;
    const double wall_h = kStorey - kSlab;

    // Outer walls with one window per room, the front door on the ground floor.
    for (int side = 0; side < 2; ++side) {
      std::vector<WallOpening> windows;
      for (int i = 0; i < density.rooms_x; ++i) {
        if (f == 0 && side == 0 && i == density.rooms_x / 2) {
          windows.push_back({i * kRoomX + 1.8, i * kRoomX + 2.8, 0, 2.1});
          continue;
        }
        windows.push_back({i * kRoomX + 1.5, i * kRoomX + 3.0, 0.9, 2.1});
      }
      const double y = side == 0 ? 0 : size_y - kOuter;
      add_wall(out, {0, y, z}, true, size_x, wall_h, kOuter, windows, rng.vary(c.outer, 5));
      for (const WallOpening& w : windows) {
        const bool door = w.bottom == 0;
        if (f == 0 || door) furnish.grille(y + kOuter * 0.5, true, w.from, w.to, z + w.bottom, z + w.top);
        if (!door)
          out.box({{w.from - 0.05, y - 0.04, z + w.bottom - 0.06},
                   {w.to + 0.05, y + kOuter + 0.04, z + w.bottom}},
                  c.frame);
      }
    }
    for (int side = 0; side < 2; ++side) {
      std::vector<WallOpening> windows;
      for (int j = 0; j < density.rooms_y; ++j)
        windows.push_back({j * kRoomY + 1.2 - kOuter, j * kRoomY + 2.6 - kOuter, 0.9, 2.1});
      const double x = side == 0 ? 0 : size_x - kOuter;
      add_wall(out, {x, kOuter, z}, false, size_y - 2 * kOuter, wall_h, kOuter, windows,
               rng.vary(c.outer, 5));
      if (f == 0)
        for (const WallOpening& w : windows)
          furnish.grille(x + kOuter * 0.5, false, w.from + kOuter, w.to + kOuter, z + w.bottom, z + w.top);
    }
    // Inner walls with a doorway into every room.
    for (int j = 1; j < density.rooms_y; ++j) {
      std::vector<WallOpening> doors;
      for (int i = 0; i < density.rooms_x; ++i) {
        const double at = i * kRoomX + rng.uniform(0.6, kRoomX - 1.6) - kOuter;
        doors.push_back({at, at + 0.9, 0, 2.1});
      }
      add_wall(out, {kOuter, j * kRoomY - kInner / 2, z}, true, size_x - 2 * kOuter, wall_h, kInner, doors,
               rng.vary(c.tints[4], 4));
    }
    for (int i = 1; i < density.rooms_x; ++i) {
      std::vector<WallOpening> doors;
      for (int j = 0; j < density.rooms_y; ++j) {
        const double at = j * kRoomY + rng.uniform(0.6, kRoomY - 1.6) - kOuter;
        doors.push_back({at, at + 0.9, 0, 2.1});
      }
      add_wall(out, {i * kRoomX - kInner / 2, kOuter, z}, false, size_y - 2 * kOuter, wall_h, kInner, doors,
               rng.vary(c.tints[4], 4));
    }
    // Rooms: a floor finish and furniture; the stairwell room gets the stair.
    for (int j = 0; j < density.rooms_y; ++j)
      for (int i = 0; i < density.rooms_x; ++i) {
        const double x0 = i * kRoomX + (i == 0 ? kOuter : kInner / 2),
                     x1 = (i + 1) * kRoomX - (i + 1 == density.rooms_x ? kOuter : kInner / 2);
        const double y0 = j * kRoomY + (j == 0 ? kOuter : kInner / 2),
                     y1 = (j + 1) * kRoomY - (j + 1 == density.rooms_y ? kOuter : kInner / 2);
        const bool stairwell = i == 0 && j + 1 == density.rooms_y;
        out.box({{x0, y0, z}, {x1, y1, z + 0.02}}, rng.vary(c.floor, 10));
        if (stairwell) {
          add_stairs(out, {x0 + 0.02, (well_y + y1) / 2, z}, {1, 0, 0}, 0.95, kStorey, tess,
                     rng.vary(c.stairs, 8));
        } else {
          furnish_room(furnish, rng, c, x0 + 0.1, y0 + 0.1, x1 - 0.1, y1 - 0.1, z + 0.02);
        }
      }
  }
}

}  // namespace cellbake
