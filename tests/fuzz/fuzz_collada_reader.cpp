// libFuzzer target: the assimp reader on arbitrary COLLADA (.dae) bytes, through
// the checks before import (markup nesting, instance counting) and our node-tree walk.
#include <exception>

#include "pipeline/readers/format_readers.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = cellbake::fuzz::input_file(data, size, "dae");
  try {
    cellbake::read_with_assimp(file, "dae", false, [](const cellbake::Triangle&) {}, {});
  } catch (const std::exception&) {
  }
  return 0;
}
