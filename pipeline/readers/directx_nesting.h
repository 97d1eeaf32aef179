// Nesting depth of DirectX .x model files in the text format, measured before
// assimp parses them (issue #37): its .x parser recurses once per nested
// frame, so a text file with Frames nested 100,000 deep overflows the stack
// inside the import (in a child process by default, pipeline/readers/
// isolated_read.h; in cellbake's own process with --import-in-process). A
// streaming count of braces outside strings and comments finds such files in
// one pass with constant memory. Binary and compressed .x files ("bin ",
// "tzip", "bzip") are left to the child process: their token stream is not
// scanned here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace cellbake {

// Counts brace nesting over the bytes of a .x file fed in order, in pieces of
// any size. The 16-byte header ("xof 0303txt 0032") decides: only the text
// format is counted.
class DirectXNestingScan {
 public:
  void feed(const char* data, std::size_t size);
  // True once the header has been read and the file is in the text format.
  bool text() const { return text_; }
  // True once the header has been read (text() is final).
  bool decided() const { return header_.size() >= kHeaderBytes; }
  // The deepest level, counted up to kMaxMarkupNesting + 1.
  int max_depth() const { return max_depth_; }
  // Byte offset at which max_depth() was first reached.
  std::uint64_t deepest_at() const { return deepest_at_; }

 private:
  static constexpr std::size_t kHeaderBytes = 16;
  void byte(char c);

  std::string header_;
  bool text_ = false;
  std::uint64_t offset_ = 0;
  int depth_ = 0, max_depth_ = 0;
  std::uint64_t deepest_at_ = 0;
  bool in_string_ = false, in_comment_ = false;
  char last_ = 0;
};

// Throws InputError naming `name` when a text .x file nests braces deeper than
// kMaxMarkupNesting (markup_nesting.h): "DirectX .x nested deeper than 2048
// levels ...". Other bytes pass.
void check_directx_nesting(const std::string& name, const char* data, std::size_t size);
// The same over a file read in pieces (plain or .gz); stops early once the
// header shows another format or a level is too deep.
void check_directx_nesting_of_file(const std::string& name, const std::filesystem::path& file);

}  // namespace cellbake
