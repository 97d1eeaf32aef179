// Building parts shared by the procedural scenes, composed from the primitives
// of scene_primitives.h through a SceneBuilder: walls with rectangular
// openings, I-beams, grated walkways, railings and stair flights. All parts
// are axis-aligned in plan (x/y), metres, +z up.
#pragma once

#include <vector>

#include "pipeline/scenes/scene_builder.h"

namespace cellbake {

// A rectangular hole in a wall: [from, to] along the wall, [bottom, top] in z.
struct WallOpening {
  double from = 0, to = 0, bottom = 0, top = 0;
};

// A straight wall whose near face starts at `start` and runs `length` metres
// along +x (along_x) or +y, `height` tall and `thickness` thick (into +y for a
// wall along x, +x for one along y). Openings must lie inside the wall and not
// overlap each other; the solid rest is emitted as boxes.
void add_wall(SceneBuilder& out, Vec3d start, bool along_x, double length, double height, double thickness,
              const std::vector<WallOpening>& openings, Rgba8 color);

// An I-beam (two flanges and a web) between points `a` and `b`, which differ in
// exactly one coordinate. `depth` is the size across the flanges (vertical for
// horizontal beams, along x for columns), `width` the flange width.
void add_i_beam(SceneBuilder& out, Vec3d a, Vec3d b, double depth, double width, Rgba8 color);

// A grated walkway over the rectangle `area` (z = walking level): edge frame,
// bearing bars across the short side every `pitch` metres, two tie bars.
void add_grating(SceneBuilder& out, const Box3d& area, double pitch, Rgba8 color);

// A railing of height `height` from `a` to `b` (same z, differing in x or y):
// posts about every 1.5 m (at the ends too when `end_posts`; leave them out
// where another railing already has a post) and two round rails.
void add_railing(SceneBuilder& out, Vec3d a, Vec3d b, double height, bool end_posts, SceneTessellation& tess,
                 Rgba8 color);

// A straight stair flight rising `rise` metres from `foot` (centre of the bottom
// edge of the first step) along the unit axis direction `run_direction` (±x or
// ±y), `width` wide, with treads, two slanted stringers and two handrails.
void add_stairs(SceneBuilder& out, Vec3d foot, Vec3d run_direction, double width, double rise,
                SceneTessellation& tess, Rgba8 color);

}  // namespace cellbake
