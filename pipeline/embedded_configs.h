// Configuration files compiled into the executable (configs/*.toml), so the
// demo runs from any working directory.
#pragma once

#include <string_view>

namespace cellbake {

// The text of configs/plant-demo.toml as it was at build time.
std::string_view embedded_plant_demo_config();

}  // namespace cellbake
