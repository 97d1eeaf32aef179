// libFuzzer target: the OBJ reader (pipeline/readers) on arbitrary file bytes.
#include <exception>

#include "pipeline/readers/format_readers.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = cellbake::fuzz::input_file(data, size, "obj");
  try {
    cellbake::read_obj(file, [](const cellbake::Triangle&) {}, {});
  } catch (const std::exception&) {
  }
  return 0;
}
