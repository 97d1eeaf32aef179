#include "viewer/camera_path.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace cellbake {

Vec3d parse_point(const std::string& text, const char* what) {
  Vec3d p;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> p.x >> c1 >> p.y >> c2 >> p.z) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof() || !is_finite(p))
    throw std::invalid_argument(std::string(what) + " must be X,Y,Z (three finite numbers), got \"" + text + "\"");
  return p;
}

std::pair<int, int> parse_image_size(const std::string& text) {
  int w = 0, h = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || (x != 'x' && x != 'X') || !(in >> std::ws).eof() || w < 1 || h < 1 || w > 16384 ||
      h > 16384)
    throw std::invalid_argument("size must be WxH with 1..16384 pixels each, got \"" + text + "\"");
  return {w, h};
}

std::vector<PathView> read_camera_path(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read camera path");
  std::vector<PathView> views;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    PathView v;
    if (!(fields >> v.eye.x >> v.eye.y >> v.eye.z >> v.look.x >> v.look.y >> v.look.z) ||
        !(fields >> std::ws).eof() || !is_finite(v.eye) || !is_finite(v.look))
      throw std::runtime_error(file.string() + ":" + std::to_string(number) +
                               ": expected six numbers \"ex ey ez lx ly lz\"");
    views.push_back(v);
  }
  if (views.empty()) throw std::runtime_error(file.string() + ": camera path holds no view");
  return views;
}

std::string camera_path_text(const std::vector<PathView>& views) {
  std::string text;
  char number[32];
  for (const PathView& v : views) {
    const double values[6] = {v.eye.x, v.eye.y, v.eye.z, v.look.x, v.look.y, v.look.z};
    for (int k = 0; k < 6; ++k) {
      const auto end = std::to_chars(number, number + sizeof number, values[k]).ptr;
      text.append(number, end);
      text += k < 5 ? ' ' : '\n';
    }
  }
  return text;
}

std::filesystem::path numbered_path(const std::filesystem::path& base, int index) {
  char suffix[16];
  std::snprintf(suffix, sizeof suffix, "_%04d", index);
  return base.parent_path() / (base.stem().string() + suffix + base.extension().string());
}

}  // namespace cellbake
