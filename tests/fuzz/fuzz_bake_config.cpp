// libFuzzer target: the TOML bake configuration (pipeline/bake_config.h:
// parse, validate, describe) on arbitrary text.
#include <exception>
#include <string_view>

#include "pipeline/bake_config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    cellbake::BakeConfig config = cellbake::parse_bake_config(text, "fuzz.toml");
    cellbake::validate_bake_config(config);
    cellbake::describe_bake_config(config);
    cellbake::effective_near_budget(config, 1000000);
  } catch (const std::exception&) {
  }
  return 0;
}
