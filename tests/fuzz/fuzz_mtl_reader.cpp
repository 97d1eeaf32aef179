// libFuzzer target: the MTL material library reader on arbitrary file bytes.
#include <exception>

#include "pipeline/readers/mtl_reader.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = cellbake::fuzz::input_file(data, size, "mtl");
  std::vector<cellbake::Material> materials;
  std::unordered_map<std::string, std::uint32_t> by_name;
  try {
    cellbake::read_mtl(file, materials, by_name);
  } catch (const std::exception&) {
  }
  for (const auto& [name, index] : by_name)
    if (index >= materials.size()) __builtin_trap();
  return 0;
}
