#include "viewer/baked_config_text.h"

#include <sstream>
#include <stdexcept>

namespace cellbake {

std::vector<Box3d> regions_of_config_text(const std::string& text) {
  std::vector<Box3d> regions;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("region=", 0) != 0) continue;
    std::istringstream values(line.substr(7));
    double v[6];
    char comma;
    for (int i = 0; i < 6; ++i) {
      if (!(values >> v[i]) || (i < 5 && !(values >> comma)) || (i < 5 && comma != ','))
        throw std::invalid_argument("verify: malformed config line \"" + line + "\"");
    }
    regions.push_back({{v[0], v[1], v[2]}, {v[3], v[4], v[5]}});
  }
  return regions;
}

std::optional<std::uint64_t> far_budget_of_config_text(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("view.far_budget=", 0) != 0) continue;
    try {
      std::size_t used = 0;
      const std::uint64_t v = std::stoull(line.substr(16), &used);
      if (used == line.size() - 16) return v;
    } catch (const std::exception&) {
    }
    throw std::invalid_argument("malformed config line \"" + line + "\"");
  }
  return std::nullopt;
}

ShadingParams shading_of_config_text(const std::string& text) {
  ShadingParams p;
  p.mode = ShadingMode::unlit;  // no shading lines: baked before shading existed
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("shading.", 0) != 0) continue;
    const std::size_t eq = line.find('=');
    const std::string key = line.substr(0, eq), value = eq == std::string::npos ? "" : line.substr(eq + 1);
    const auto malformed = [&]() { return std::invalid_argument("malformed config line \"" + line + "\""); };
    const auto scalar = [&]() {
      std::istringstream v(value);
      double d;
      if (!(v >> d) || !(v >> std::ws).eof()) throw malformed();
      return d;
    };
    const auto vector = [&]() {
      std::istringstream v(value);
      Vec3d d;
      char comma1 = 0, comma2 = 0;
      if (!(v >> d.x >> comma1 >> d.y >> comma2 >> d.z) || comma1 != ',' || comma2 != ',' || !(v >> std::ws).eof())
        throw malformed();
      return d;
    };
    if (key == "shading.mode") {
      try {
        p.mode = parse_shading_mode(value);
      } catch (const std::invalid_argument&) {
        throw malformed();
      }
    } else if (key == "shading.key_direction") {
      p.key_direction = vector();
    } else if (key == "shading.fill_direction") {
      p.fill_direction = vector();
    } else if (key == "shading.key_strength") {
      p.key_strength = scalar();
    } else if (key == "shading.fill_strength") {
      p.fill_strength = scalar();
    } else if (key == "shading.ambient") {
      p.ambient = scalar();
    }
  }
  return p;
}

}  // namespace cellbake
