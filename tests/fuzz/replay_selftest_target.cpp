// A target with planted findings for the replay driver's own test
// (replay_selftest.cmake): input "TRAP..." traps, "THROW..." lets an exception
// escape, and any input of 1..3 bytes traps (only mutants of a longer seed
// reach it); everything else is accepted.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size >= 4 && std::memcmp(data, "TRAP", 4) == 0) __builtin_trap();
  if (size >= 5 && std::memcmp(data, "THROW", 5) == 0) throw std::runtime_error("planted");
  if (size >= 1 && size <= 3) __builtin_trap();
  return 0;
}
