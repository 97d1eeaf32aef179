// Text forms of viewer inputs: "X,Y,Z" points, "WxH" sizes and camera path
// files (one view per line: "ex ey ez lx ly lz"; blank lines and lines
// starting with '#' are skipped).
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "stages/geometry.h"

namespace cellbake {

struct PathView {
  Vec3d eye, look;
};

// Parses "X,Y,Z" (three finite numbers). Throws std::invalid_argument naming `what`.
Vec3d parse_point(const std::string& text, const char* what);
// Parses "WxH" (1..16384 each). Throws std::invalid_argument.
std::pair<int, int> parse_image_size(const std::string& text);
// Reads a camera path. Throws std::runtime_error("FILE:LINE: ...") on a
// malformed line and when the file cannot be read or holds no view.
std::vector<PathView> read_camera_path(const std::filesystem::path& file);
// The text of a camera path file holding `views`, one "ex ey ez lx ly lz"
// line each, numbers in their shortest form that reads back exactly.
std::string camera_path_text(const std::vector<PathView>& views);
// "dir/name.png", 7 -> "dir/name_0007.png".
std::filesystem::path numbered_path(const std::filesystem::path& base, int index);

}  // namespace cellbake
