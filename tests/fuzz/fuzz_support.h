// Shared by the libFuzzer targets (tests/fuzz/README in docs/reliability.md):
// readers that take a path get the fuzz input as a file in a private temporary
// folder of this process. Every target treats a thrown std::exception as the
// expected answer to bad bytes; anything else (a sanitizer report, abort, a
// timeout, running out of memory) is a finding.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

namespace cellbake::fuzz {

// DIR/input.EXT holding the `size` bytes at `data`; DIR is created once per
// process under the temporary directory and removed at exit.
inline std::filesystem::path input_file(const std::uint8_t* data, std::size_t size, const std::string& ext) {
  struct Dir {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("cellbake-fuzz-" + std::to_string(::getpid()));
    Dir() { std::filesystem::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static Dir dir;
  const std::filesystem::path file = dir.path / ("input." + ext);
  std::FILE* out = std::fopen(file.c_str(), "wb");
  if (!out) std::abort();
  if (size && std::fwrite(data, 1, size, out) != size) std::abort();
  std::fclose(out);
  return file;
}

}  // namespace cellbake::fuzz
