// The error type for bad input: every message names the file, the place in it
// (line or byte offset) and what is wrong, so a user can find and fix it.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace cellbake {

class InputError : public std::runtime_error {
 public:
  // `where` is e.g. "line 12" or "byte 4096"; may be empty when the whole file is at fault.
  InputError(const std::string& file, const std::string& where, const std::string& what)
      : std::runtime_error(file + (where.empty() ? "" : ":" + where) + ": " + what) {}
};

inline std::string at_line(std::uint64_t line) { return "line " + std::to_string(line); }
inline std::string at_byte(std::uint64_t offset) { return "byte " + std::to_string(offset); }

}  // namespace cellbake
