// Layout of the city scene (see scene_city.h).
#include "pipeline/scenes/scene_city.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "pipeline/scenes/scene_math.h"
#include "pipeline/scenes/scene_random.h"

namespace cellbake {
namespace {

constexpr double kBlock = 60, kStreet = 20, kPitch = kBlock + kStreet, kFloor = 3.5;

struct Palette {
  Rgba8 road{60, 60, 64, 255}, marking{235, 235, 225, 255}, sidewalk{175, 172, 165, 255};
  Rgba8 trunk{95, 70, 45, 255}, crown{60, 120, 55, 255}, lamp{70, 75, 80, 255}, roof{110, 105, 100, 255};
  Rgba8 facades[6] = {{200, 190, 170, 255}, {150, 160, 175, 255}, {180, 120, 90, 255},
                      {220, 220, 215, 255}, {120, 130, 120, 255}, {170, 150, 130, 255}};
  Rgba8 glass{70, 95, 120, 255};
};

struct CityDensity {
  int blocks;            // per side
  double mullion_pitch;  // metres between window mullions
  explicit CityDensity(const SceneDensity& density) {
    const double g = std::sqrt(std::sqrt(density.structure));
    blocks = static_cast<int>(std::clamp(std::floor(2.0 * g), 2.0, 400.0));
    mullion_pitch = std::clamp(6.0 / std::sqrt(density.tessellation), 0.6, 6.0);
  }
};

void tree(SceneBuilder& out, SceneRng& rng, SceneTessellation& tess, const Palette& c, Vec3d base) {
  const double h = rng.uniform(3.0, 5.0), r = rng.uniform(1.2, 2.0);
  const LatheSample trunk[4] = {{0, 0}, {0.15, 0}, {0.12, h}, {0, h}};
  out.lathe(base, {0, 0, 1}, trunk, tess.circle_segments(0.15, 5), rng.vary(c.trunk, 10));
  const int rings = std::max(2, tess.bend_segments(r) * 2);
  std::vector<LatheSample> crown{{0, 0}};
  for (int k = 1; k < rings; ++k) {
    const SinCos a = sin_cos_turns(0.5 * k / rings);  // half a turn: bottom pole to top pole
    crown.push_back({r * a.s, r * (1 - a.c)});
  }
  crown.push_back({0, 2 * r});
  out.lathe(base + Vec3d{0, 0, h - 0.4 * r}, {0, 0, 1}, crown, tess.circle_segments(r, 6),
            rng.vary(c.crown, 18));
}

void street_lamp(SceneBuilder& out, SceneTessellation& tess, const Palette& c, Vec3d base, Vec3d arm) {
  PipeStyle pole;
  pole.radius = 0.08;
  pole.bend_radius = 0.3;
  pole.segments = tess.circle_segments(pole.radius, 5);
  pole.bend_segments = tess.bend_segments(pole.bend_radius);
  const Vec3d path[3] = {base, base + Vec3d{0, 0, 6}, base + Vec3d{0, 0, 6} + arm * 1.2};
  out.pipe(path, pole, c.lamp);
  const Vec3d head = path[2] + arm * 0.2;
  out.box({{head.x - 0.25, head.y - 0.25, 5.8}, {head.x + 0.25, head.y + 0.25, 6.0}}, c.marking);
}

// A building on footprint [x0, x1] x [y0, y1] with `floors` storeys: body,
// per-floor ledges and mullions on every facade, parapet and roof equipment.
void building(SceneBuilder& out, SceneRng& rng, SceneTessellation& tess, const Palette& c,
              const CityDensity& density, double x0, double y0, double x1, double y1, int floors) {
  const double height = floors * kFloor;
  const Rgba8 facade = rng.vary(c.facades[rng.below(6)], 10);
  const Rgba8 trim = rng.vary(facade, 25);
  out.box({{x0, y0, 0}, {x1, y1, height}}, rng.vary(c.glass, 8));
  const double fin = 0.12, ledge = 0.3;
  for (int f = 0; f < floors; ++f) {
    const double z = f * kFloor;
    out.box({{x0 - fin, y0 - fin, z}, {x1 + fin, y1 + fin, z + ledge}}, trim);  // ledge band all round
    // Mullions on the four facades.
    auto mullions = [&](double from, double to, auto place) {
      const int n = std::max(1, static_cast<int>(std::floor((to - from) / density.mullion_pitch)));
      for (int i = 0; i <= n; ++i) place(from + 0.1 + (to - from - 0.2) * i / n);
    };
    const double z0 = z + ledge, z1 = z + kFloor;
    mullions(x0, x1, [&](double x) {
      out.box({{x - 0.08, y0 - fin, z0}, {x + 0.08, y0, z1}}, facade);
      out.box({{x - 0.08, y1, z0}, {x + 0.08, y1 + fin, z1}}, facade);
    });
    mullions(y0, y1, [&](double y) {
      out.box({{x0 - fin, y - 0.08, z0}, {x0, y + 0.08, z1}}, facade);
      out.box({{x1, y - 0.08, z0}, {x1 + fin, y + 0.08, z1}}, facade);
    });
  }
  // Parapet and roof equipment.
  out.box({{x0, y0, height}, {x1, y0 + 0.3, height + 1.0}}, trim);
  out.box({{x0, y1 - 0.3, height}, {x1, y1, height + 1.0}}, trim);
  out.box({{x0, y0 + 0.3, height}, {x0 + 0.3, y1 - 0.3, height + 1.0}}, trim);
  out.box({{x1 - 0.3, y0 + 0.3, height}, {x1, y1 - 0.3, height + 1.0}}, trim);
  const int units = 1 + static_cast<int>(rng.below(3));
  for (int u = 0; u < units; ++u) {
    const double ux = rng.uniform(x0 + 1.5, x1 - 4.0), uy = rng.uniform(y0 + 1.5, y1 - 3.5);
    out.box({{ux, uy, height}, {ux + 2.5, uy + 2.0, height + rng.uniform(1.2, 2.5)}}, c.roof);
  }
  if (floors >= 8 && rng.chance(0.5)) {
    const double r = 1.6;
    const LatheSample tank[6] = {{0, 0}, {r, 0}, {r, 2.5}, {r * 0.6, 3.1}, {0.2, 3.3}, {0, 3.3}};
    out.lathe({(x0 + x1) / 2 + 2, (y0 + y1) / 2 + 2, height}, {0, 0, 1}, tank, tess.circle_segments(r, 8),
              c.roof);
  }
}

}  // namespace

void build_city_scene(const SceneDensity& scene_density, std::uint64_t seed, SceneBuilder& out) {
  const CityDensity density(scene_density);
  SceneRng rng(seed);
  SceneTessellation tess(0.03 / scene_density.tessellation, 0, seed);
  const Palette c;
  const int n = density.blocks;
  const double extent = n * kPitch + kStreet;
  // One road surface under the whole city; blocks (sidewalk slabs) sit on it.
  out.box({{-kStreet, -kStreet, -0.4}, {extent, extent, 0}}, c.road);
  const double centre = (n - 1) * 0.5;
  for (int by = 0; by < n; ++by)
    for (int bx = 0; bx < n; ++bx) {
      const double x0 = bx * kPitch + kStreet, y0 = by * kPitch + kStreet;
      // Dashed centre lines of the streets west and south of the block (and on the far sides).
      auto road = [&](double rx0, double ry0, double rx1, double ry1, bool along_x) {
        const double from = along_x ? rx0 : ry0, to = along_x ? rx1 : ry1,
                     mid = along_x ? (ry0 + ry1) / 2 : (rx0 + rx1) / 2;
        for (double s = from + 1.5; s + 3 <= to - 1.5; s += 6)
          out.box(along_x ? Box3d{{s, mid - 0.08, 0}, {s + 3, mid + 0.08, 0.01}}
                          : Box3d{{mid - 0.08, s, 0}, {mid + 0.08, s + 3, 0.01}},
                  c.marking);
      };
      road(x0 - kStreet, y0 - kStreet, x0 + kBlock, y0, true);
      road(x0 - kStreet, y0, x0, y0 + kBlock, false);
      if (bx + 1 == n) road(x0 + kBlock, y0 - kStreet, x0 + kBlock + kStreet, y0 + kBlock + kStreet, false);
      if (by + 1 == n) road(x0 - kStreet, y0 + kBlock, x0 + kBlock, y0 + kBlock + kStreet, true);
      out.box({{x0, y0, 0}, {x0 + kBlock, y0 + kBlock, 0.15}}, rng.vary(c.sidewalk, 5));
      // Trees and lamps along the block edges.
      for (double s = 5; s < kBlock; s += 10) {
        tree(out, rng, tess, c, {x0 + s, y0 + 1.5, 0.15});
        tree(out, rng, tess, c, {x0 + 1.5, y0 + s, 0.15});
      }
      street_lamp(out, tess, c, {x0 + kBlock - 1.0, y0 + 1.0, 0.15}, {0, -1, 0});
      street_lamp(out, tess, c, {x0 + 1.0, y0 + kBlock - 1.0, 0.15}, {-1, 0, 0});
      // Parcels: 1-3 by 1-2, each with a building set back from its edges; taller near the centre.
      const double distance =
          std::max(std::fabs(bx - centre), std::fabs(by - centre)) / std::max(1.0, centre + 0.5);
      const int parcels_x = 1 + static_cast<int>(rng.below(3)),
                parcels_y = 1 + static_cast<int>(rng.below(2));
      for (int py = 0; py < parcels_y; ++py)
        for (int px = 0; px < parcels_x; ++px) {
          const double w = (kBlock - 6) / parcels_x, d = (kBlock - 6) / parcels_y;
          const double bx0 = x0 + 3 + px * w + rng.uniform(1, 2.5),
                       bx1 = x0 + 3 + (px + 1) * w - rng.uniform(1, 2.5);
          const double by0 = y0 + 3 + py * d + rng.uniform(1, 2.5),
                       by1 = y0 + 3 + (py + 1) * d - rng.uniform(1, 2.5);
          const int floors = 3 + static_cast<int>(rng.below(4)) +
                             static_cast<int>(std::floor((1 - distance) * 20 * rng.unit()));
          building(out, rng, tess, c, density, bx0, by0, bx1, by1, floors);
        }
    }
}

}  // namespace cellbake
