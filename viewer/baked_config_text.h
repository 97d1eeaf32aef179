// What a cell database's meta `config` text (describe_bake_config: one
// "key=value" line per parameter) says about the bake that the viewers and
// `cellbake verify` need: its regions, view.far_budget and light model.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "stages/geometry.h"
#include "stages/shading.h"

namespace cellbake {

// The regions ("region=x0,y0,z0,x1,y1,z1" lines) of a cell database's meta
// `config` text (describe_bake_config), in order; lines that are not regions
// are ignored. Throws std::invalid_argument for a malformed region line.
std::vector<Box3d> regions_of_config_text(const std::string& config_text);

// The `view.far_budget` of a cell database's meta `config` text, if it has
// one (databases baked before it existed do not). Throws
// std::invalid_argument for a malformed value.
std::optional<std::uint64_t> far_budget_of_config_text(const std::string& config_text);

// The light model a cell database was baked with, from its meta `config`
// text (the shading.* lines describe_bake_config writes; directions in the
// up-axis frame). Databases baked before shading existed have no such lines
// and were baked unlit: then mode is unlit (and the rest ShadingParams{}).
// Throws std::invalid_argument for a malformed shading line.
ShadingParams shading_of_config_text(const std::string& config_text);

}  // namespace cellbake
