// libFuzzer target: decode_triangle_list (stages/encode/encode_triangle_list.h), the
// far geometry's triangle numbers, on arbitrary bytes; a list that decodes is
// strictly ascending and encodes back to a blob that decodes to itself.
#include <exception>
#include <span>

#include "stages/encode/encode_triangle_list.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint32_t> list;
  try {
    list = cellbake::decode_triangle_list(std::span(data, size));
  } catch (const std::exception&) {
    return 0;
  }
  for (std::size_t i = 1; i < list.size(); ++i)
    if (list[i - 1] >= list[i]) __builtin_trap();
  if (cellbake::decode_triangle_list(cellbake::encode_triangle_list(list)) != list) __builtin_trap();
  return 0;
}
