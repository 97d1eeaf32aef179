// Procedural test scenes that look like what users walk through: an industrial
// plant hall, a house, a city block grid. Deterministic for a given seed and
// scalable from ~100 k to 100 M triangles (the scene is emitted in parts, so
// memory stays bounded by the largest part, not the scene).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "stages/geometry.h"

namespace cellbake {

enum class SceneKind { plant, house, city };

struct SceneParams {
  SceneKind kind = SceneKind::plant;
  std::uint64_t target_triangles = 2'000'000;  // the result is within ~10 % of this
  std::uint64_t seed = 1;
};

struct SceneSummary {
  std::uint64_t triangles = 0;
  std::uint64_t vertices = 0;
  Box3d bounds;  // metres, z up
};

// Parses "plant" / "house" / "city"; throws std::invalid_argument otherwise.
SceneKind parse_scene_kind(const std::string& name);

// Generates the scene and hands it to `emit` as a sequence of indexed meshes
// (each part's indices refer to that part's own positions; every part has
// per-vertex colours). Units are metres, +z is up. Same params -> same parts,
// bit for bit, on every machine and thread count.
SceneSummary generate_scene(const SceneParams& params, const std::function<void(const TriangleMesh&)>& emit);

}  // namespace cellbake
