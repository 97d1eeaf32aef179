// The message a model read ends with, for tests of readers' refusals.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "pipeline/input_error.h"
#include "pipeline/readers/model_reader.h"

namespace cellbake::test {

// The message of the InputError read_model throws for `file`, or "" when it
// reads (then `triangles`, when given, receives the triangles emitted).
inline std::string read_error(const std::filesystem::path& file, std::uint64_t* triangles = nullptr) {
  try {
    const ModelInfo info = read_model(file, [](const Triangle&) {});
    if (triangles) *triangles = info.triangles_emitted;
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

}  // namespace cellbake::test
