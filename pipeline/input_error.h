// The error type for bad input: every message names the file, the place in it
// (line or byte offset) and what is wrong, so a user can find and fix it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace cellbake {

class InputError : public std::runtime_error {
 public:
  // `where` is e.g. "line 12" or "byte 4096"; may be empty when the whole file is at fault.
  InputError(const std::string& file, const std::string& where, const std::string& what)
      : std::runtime_error(file + (where.empty() ? "" : ":" + where) + ": " + what) {}
  // An error whose whole message is already formed (one InputError's what(),
  // carried across a process boundary: pipeline/readers/isolated_read.h).
  struct Formed {};
  InputError(Formed, const std::string& message) : std::runtime_error(message) {}
};

inline std::string at_line(std::uint64_t line) { return "line " + std::to_string(line); }
inline std::string at_byte(std::uint64_t offset) { return "byte " + std::to_string(offset); }

// Throws InputError unless `file` is a regular file (or a link to one):
// "no such file", or "not a regular file (a directory)" / "(a pipe)" /
// "(a device)" / "(a socket)", so a FIFO is never opened (it would block).
inline void require_regular_file(const std::filesystem::path& file) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (fs::is_regular_file(st)) return;
  if (!fs::exists(st)) throw InputError(file.string(), "", "no such file");
  const char* kind = fs::is_directory(st) ? "a directory"
                     : fs::is_fifo(st)    ? "a pipe"
                     : fs::is_socket(st)  ? "a socket"
                     : (fs::is_block_file(st) || fs::is_character_file(st)) ? "a device"
                                                                             : "not a file";
  throw InputError(file.string(), "", std::string("not a regular file (") + kind + ")");
}

}  // namespace cellbake
