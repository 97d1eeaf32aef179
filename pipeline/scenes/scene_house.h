// The "house" scene: a building of furnished rooms in the spirit of the Brooks
// House model of Wilson's thesis (2002, §1.1). Floors of rooms laid out on a
// grid, with real wall thickness, doorways, windows (ground-floor windows and
// the front door behind grilles of thin bars), a stair per floor, and
// furniture made of boxes and turned parts: tables, chairs, cupboards, beds,
// sofas, lamps, vases.
#pragma once

#include <cstdint>

#include "pipeline/scenes/scene_builder.h"

namespace cellbake {

// Emits the house: more `structure` means more floors and rooms per floor
// (the building grows), more `tessellation` rounder turned parts and finer
// bars. Deterministic in (density, seed).
void build_house_scene(const SceneDensity& density, std::uint64_t seed, SceneBuilder& out);

}  // namespace cellbake
