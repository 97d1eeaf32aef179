// The one lighting model every chunk drawing uses (the sampler, `render`
// truth and impostor near field, `verify`, `cellbake-view`): fixed and
// view-independent, so a colour baked into a panoramic sample is the colour
// the ground truth shows from anywhere. Two directional lights plus ambient,
// Lambertian and two-sided, no headlight:
//
//   lit = clamp(base * (ambient + key_strength * |n . key| + fill_strength * |n . fill|), 0, 1)
//
// per R, G, B (alpha is kept), with n the unit face normal. ChunkRenderer
// evaluates it per fragment with flat face normals from screen-space
// derivatives of the eye-relative position (cross(dFdx, dFdy)); the far
// field's textured depth meshes show the lit colours baked into the sample
// images and are not lit again. Per-vertex normals from model files (OBJ vn,
// PLY nx ny nz, glTF) would need a geometry-store schema change and are not
// used. Pure code: no GL.
#pragma once

#include <string>

#include "stages/geometry.h"

namespace cellbake {

enum class ShadingMode {
  lit,    // the light model above
  unlit,  // the base (vertex) colour as it is: the look of bakes before shading existed
};

// The light model as configured ([shading] in a bake config), in the model's
// up-axis frame: x, y as stored, z along the model's up axis (config
// `model.up`). Directions need not be unit length (they are normalised) and
// their sign does not matter (the lighting is two-sided). Defaults: a key
// light from high above at an angle and a weaker fill from the other side,
// chosen so that horizontal surfaces show ~0.96 of their colour, walls facing
// x ~0.76 and walls facing y ~0.58 (axis-aligned rooms read as solid), no
// orientation exceeds 0.98 (nothing saturates) and none falls below ~0.32.
struct ShadingParams {
  ShadingMode mode = ShadingMode::lit;
  Vec3d key_direction{0.4, 0.3, 1.0};
  double key_strength = 0.6;
  Vec3d fill_direction{-1.0, -0.5, 0.5};
  double fill_strength = 0.3;
  double ambient = 0.3;
};

// The light model in world axes, as ChunkRenderer applies it: unit directions.
struct ShadingLights {
  bool lit = true;
  Vec3d key{0, 0, 1}, fill{0, 0, 1};  // unit length, world axes
  double key_strength = 0, fill_strength = 0, ambient = 1;
};

// "lit" | "unlit", and back (throws std::invalid_argument for anything else).
const char* shading_mode_name(ShadingMode mode);
ShadingMode parse_shading_mode(const std::string& name);

// Maps `params` from the up-axis frame to world axes for a model whose up axis
// is `up`: (0, 0, 1) keeps them; (0, 1, 0) rotates the frame's z onto world y
// (x, y, z) -> (x, z, -y), a proper rotation, so a z-up scene rotated into y-up
// is lit the same. Throws std::invalid_argument for another up vector, a zero
// or non-finite direction, or a negative or non-finite strength.
ShadingLights shading_lights(const ShadingParams& params, const Vec3d& up);

// The factor base colours are multiplied by for a surface with normal `normal`
// (any length > 0, either orientation): ambient + sum strength * |n . l| when
// lit, 1 when unlit. The shader computes the same in float.
double lighting_factor(const ShadingLights& lights, const Vec3d& normal);

// `base` lit with `factor` (lighting_factor()): R, G, B multiplied and clamped
// to [0, 255], rounded to nearest; alpha kept.
Rgba8 apply_lighting(const Rgba8& base, double factor);

}  // namespace cellbake
