#include "stages/shading.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cellbake {
namespace {

Vec3d unit_direction(const Vec3d& v, const char* name) {
  const double n = length(v);
  if (!is_finite(v) || !(n > 0) || !std::isfinite(n))
    throw std::invalid_argument(std::string("shading: ") + name + " must be a finite, non-zero vector");
  return v * (1.0 / n);
}

double strength(double s, const char* name) {
  if (!(s >= 0) || !std::isfinite(s))
    throw std::invalid_argument(std::string("shading: ") + name + " must be finite and >= 0, got " +
                                std::to_string(s));
  return s;
}

}  // namespace

const char* shading_mode_name(ShadingMode mode) { return mode == ShadingMode::unlit ? "unlit" : "lit"; }

ShadingMode parse_shading_mode(const std::string& name) {
  if (name == "lit") return ShadingMode::lit;
  if (name == "unlit") return ShadingMode::unlit;
  throw std::invalid_argument("shading: mode must be \"lit\" or \"unlit\", got \"" + name + "\"");
}

ShadingLights shading_lights(const ShadingParams& p, const Vec3d& up) {
  const bool z_up = up == Vec3d{0, 0, 1}, y_up = up == Vec3d{0, 1, 0};
  if (!z_up && !y_up) throw std::invalid_argument("shading: up must be (0, 0, 1) or (0, 1, 0)");
  const auto to_world = [&](const Vec3d& v) { return z_up ? v : Vec3d{v.x, v.z, -v.y}; };
  ShadingLights l;
  l.lit = p.mode == ShadingMode::lit;
  l.key = to_world(unit_direction(p.key_direction, "key_direction"));
  l.fill = to_world(unit_direction(p.fill_direction, "fill_direction"));
  l.key_strength = strength(p.key_strength, "key_strength");
  l.fill_strength = strength(p.fill_strength, "fill_strength");
  l.ambient = strength(p.ambient, "ambient");
  return l;
}

double lighting_factor(const ShadingLights& l, const Vec3d& normal) {
  if (!l.lit) return 1.0;
  const Vec3d n = normal * (1.0 / length(normal));
  return l.ambient + l.key_strength * std::abs(dot(n, l.key)) + l.fill_strength * std::abs(dot(n, l.fill));
}

Rgba8 apply_lighting(const Rgba8& base, double factor) {
  const auto channel = [factor](std::uint8_t c) {
    const double v = std::clamp(c * factor, 0.0, 255.0);
    return static_cast<std::uint8_t>(std::lround(v));
  };
  return {channel(base.r), channel(base.g), channel(base.b), base.a};
}

}  // namespace cellbake
