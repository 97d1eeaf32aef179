// libFuzzer target: the assimp reader on arbitrary .x3d bytes, through the
// checks before import (markup nesting) and our node-tree walk.
#include <exception>

#include "pipeline/readers/format_readers.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = cellbake::fuzz::input_file(data, size, "x3d");
  try {
    cellbake::read_with_assimp(file, "x3d", false, [](const cellbake::Triangle&) {}, {});
  } catch (const std::exception&) {
  }
  return 0;
}
