// The "plant" scene: an industrial hall in the spirit of the coal-fired power
// plant of Wilson's thesis (2002, ch. 7: 12.7 M triangles, dense arrays of long
// thin pipes in the middle). A fixed 60 x 40 x 30 m hall with walls, windows
// and doors, mezzanine floors, grated walkways, steel columns and girders,
// stairs, tanks, machinery, pipe racks with bent pipe runs, and a furnace
// block of tightly spaced tubes (waterwalls and serpentine tube banks).
#pragma once

#include <cstdint>

#include "pipeline/scenes/scene_builder.h"

namespace cellbake {

// Emits the plant into `out` (about 70 k triangles at density 1, growing with
// both density numbers). Deterministic in (density, seed).
void build_plant_scene(const SceneDensity& density, std::uint64_t seed, SceneBuilder& out);

}  // namespace cellbake
