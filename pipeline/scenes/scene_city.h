// The "city" scene: a street grid of blocks with buildings of varied heights
// (taller towards the centre, deterministic from the seed), roads with lane
// markings, sidewalks, street trees and lamps. Facades carry per-floor window
// bands as geometry (ledges and mullions).
#pragma once

#include <cstdint>

#include "pipeline/scenes/scene_builder.h"

namespace cellbake {

// Emits the city: more `structure` means more blocks (the city grows
// outwards), more `tessellation` finer facade subdivision and rounder trees.
// Deterministic in (density, seed).
void build_city_scene(const SceneDensity& density, std::uint64_t seed, SceneBuilder& out);

}  // namespace cellbake
