#include "pipeline/bake_parameters.h"

#include <charconv>
#include <map>
#include <sstream>
#include <type_traits>

namespace cellbake {
namespace {

using T = ParameterType;
using H = HashStage;

constexpr double kInt40 = double(std::int64_t(1) << 40);
constexpr double kInt24 = double(std::int64_t(1) << 24);
constexpr double kInt20 = double(std::int64_t(1) << 20);

// A row whose value is the BakeConfig member `m` (an integer, floating-point,
// string or path member).
template <typename M>
BakeParameter field(std::string key, std::string described, ParameterType type, double lo, double hi,
                    std::vector<std::string> allowed, HashStage hash, std::string doc, M BakeConfig::*m) {
  BakeParameter p{std::move(key), std::move(described), type, lo, hi, std::move(allowed), hash, std::move(doc), {}, {}};
  if constexpr (std::is_integral_v<M>) {
    p.get = [m](const BakeConfig& c) -> ParameterValue { return std::int64_t(c.*m); };
    p.put = [m](BakeConfig& c, const ParameterValue& v) { c.*m = static_cast<M>(std::get<std::int64_t>(v)); };
  } else if constexpr (std::is_floating_point_v<M>) {
    p.get = [m](const BakeConfig& c) -> ParameterValue { return double(c.*m); };
    p.put = [m](BakeConfig& c, const ParameterValue& v) { c.*m = std::get<double>(v); };
  } else if constexpr (std::is_same_v<M, std::filesystem::path>) {
    p.get = [m](const BakeConfig& c) -> ParameterValue { return (c.*m).string(); };
    p.put = [m](BakeConfig& c, const ParameterValue& v) { c.*m = std::filesystem::path(std::get<std::string>(v)); };
  } else {
    static_assert(std::is_same_v<M, std::string>);
    p.get = [m](const BakeConfig& c) -> ParameterValue { return c.*m; };
    p.put = [m](BakeConfig& c, const ParameterValue& v) { c.*m = std::get<std::string>(v); };
  }
  return p;
}

// A row for a `[shading]` member (a number or a direction).
template <typename M>
BakeParameter shading(std::string key, ParameterType type, double lo, double hi, std::string doc,
                      M ShadingParams::*m) {
  BakeParameter p{key, key, type, lo, hi, {}, H::sample, std::move(doc), {}, {}};
  p.get = [m](const BakeConfig& c) -> ParameterValue { return c.shading.*m; };
  p.put = [m](BakeConfig& c, const ParameterValue& v) { c.shading.*m = std::get<M>(v); };
  return p;
}

std::vector<BakeParameter> make_table() {
  std::vector<BakeParameter> t;
  {
    BakeParameter up{"model.up", "up", T::text, 0, 0, {"z", "y"}, H::sample,
                     "The model's up axis: cell layers stack along it and [shading] directions are in its frame "
                     "(not given: the geometry store's recorded axis); lit samples hash it", {}, {}};
    up.get = [](const BakeConfig& c) -> ParameterValue { return c.up; };
    up.put = [](BakeConfig& c, const ParameterValue& v) {
      c.up = std::get<std::string>(v);
      c.up_given = true;
    };
    t.push_back(std::move(up));
  }
  t.push_back(field("cells.size", "cells.size", T::number, 1e-6, 1e9, {}, H::cell_grid,
                    "Edge of a cubic view cell, model units", &BakeConfig::cell_size));
  t.push_back(field("near.budget", "near.budget", T::integer, 0, kInt40, {}, H::cull,
                    "Near-field triangle budget per cell (thesis: 100,000)", &BakeConfig::near_budget));
  t.push_back(field("near.budget_fraction", "near.budget_fraction", T::number, 0, 1, {}, H::cull,
                    "A small model's near budget is this fraction of its triangles instead (at least 4096; 0: "
                    "near.budget as is); enters the cull hash through the effective budget",
                    &BakeConfig::near_budget_fraction));
  t.push_back(field("far.choice", "far.choice", T::text, 0, 0, {"cheapest", "tdm", "geometry"}, H::far_choice,
                    "How each face tile's far field is drawn: exact geometry where it costs no more than the depth "
                    "meshes (cheapest), depth meshes only (tdm), or geometry", &BakeConfig::far_choice));
  t.push_back(field("far.geometry_below", "far.geometry_below", T::integer, 0, kInt40, {}, H::far_choice,
                    "A far field of at most this many triangles is drawn as geometry without taking samples",
                    &BakeConfig::far_geometry_below));
  t.push_back(field("far.seen_geometry_below", "far.seen_geometry_below", T::integer, 0, kInt40, {}, H::far_choice,
                    "A far field whose seen geometry (levels included) is at most this many triangles is drawn as that "
                    "geometry without building depth meshes (0: always the per-tile choice)",
                    &BakeConfig::far_seen_geometry_below));
  t.push_back(field("far.seen_geometry_per_hit", "far.seen_geometry_per_hit", T::number, 0, 1e6, {}, H::far_choice,
                    "... and at most this many triangles per pixel the samples hit (0: always the per-tile choice)",
                    &BakeConfig::far_seen_geometry_per_hit));
  t.push_back(field("far.seen_rings", "far.seen_rings", T::integer, 0, 8, {}, H::far_choice,
                    "Rings of vertex-sharing triangles grown around the samples' hits before they stand in for "
                    "depth meshes", &BakeConfig::far_seen_rings));
  t.push_back(field("far.lod_error_px", "far.lod_error_px", T::number, 0, 64, {}, H::far_choice,
                    "A far chunk may be drawn at the coarsest stored level whose error from the cell is at most this "
                    "many face pixels (0: exact geometry only)", &BakeConfig::far_lod_error_px));
  t.push_back(field("far.lod_replaces_exact", "far.lod_replaces_exact", T::text, 0, 0, {"on", "off", "auto"},
                    H::far_choice,
                    "Whether a level may replace a chunk's exact seen triangles where it costs fewer (auto: where "
                    "its triangles are thinner than a face pixel)", &BakeConfig::far_lod_replaces_exact));
  t.push_back(field("far.geometry_factor", "far.geometry_factor", T::number, 0, 1e6, {}, H::far_choice,
                    "A tile takes exact geometry when it costs at most this many times the depth-mesh triangles it "
                    "replaces", &BakeConfig::far_geometry_factor));
  t.push_back(field("sample.face_size", "sample.face_size", T::integer, 8, 4096, {}, H::sample,
                    "Stored cube-face resolution, pixels", &BakeConfig::face_size));
  t.push_back(field("sample.supersample", "sample.supersample", T::integer, 1, 4, {}, H::sample,
                    "Render at face_size * supersample and box-filter down", &BakeConfig::supersample));
  t.push_back(field("sample.near_plane", "sample.near_plane", T::number, 1e-6, 1e3, {}, H::sample,
                    "Near clipping plane of the samples, model units", &BakeConfig::near_plane));
  t.push_back(field("sample.seam_shell_px", "sample.seam_shell_px", T::number, 0, 64, {}, H::sample,
                    "The far field reaches this many pixel footprints inside the cull box, so it overlaps the near "
                    "field without a seam", &BakeConfig::seam_shell_px));
  t.push_back(field("sample.backend", "sample.backend", T::text, 0, 0, {"osmesa", "egl", "embree", "auto"}, H::sample,
                    "Who renders the samples; the hash tells the ray caster (embree) from the GL rasterisers",
                    &BakeConfig::sample_backend));
  t.push_back(field("sample.embree_cache_mb", "sample.embree_cache_mb", T::integer, 64, kInt24, {}, H::none,
                    "Byte cap of the Embree backend's shared BVH cache, MiB (memory and speed, not pixels)",
                    &BakeConfig::embree_cache_mb));
  t.push_back(field("sample.texture_cache_mb", "sample.texture_cache_mb", T::integer, 16, kInt24, {}, H::none,
                    "Byte cap of the decoded textures a bake holds, MiB (memory and speed, not pixels)",
                    &BakeConfig::texture_cache_mb));
  {
    BakeParameter mode{"shading.mode", "shading.mode", T::text, 0, 0, {"lit", "unlit"}, H::sample,
                       "The light model every chunk drawing applies; unlit keeps vertex colours as they are", {}, {}};
    mode.get = [](const BakeConfig& c) -> ParameterValue { return std::string(shading_mode_name(c.shading.mode)); };
    mode.put = [](BakeConfig& c, const ParameterValue& v) { c.shading.mode = parse_shading_mode(std::get<std::string>(v)); };
    t.push_back(std::move(mode));
  }
  t.push_back(shading("shading.key_direction", T::direction, 0, 0,
                      "Direction towards the key light, in the up-axis frame (any length)", &ShadingParams::key_direction));
  t.push_back(shading("shading.key_strength", T::number, 0, 2, "Strength of the key light", &ShadingParams::key_strength));
  t.push_back(shading("shading.fill_direction", T::direction, 0, 0,
                      "Direction towards the fill light, in the up-axis frame (any length)", &ShadingParams::fill_direction));
  t.push_back(shading("shading.fill_strength", T::number, 0, 2, "Strength of the fill light", &ShadingParams::fill_strength));
  t.push_back(shading("shading.ambient", T::number, 0, 2, "Ambient light", &ShadingParams::ambient));
  t.push_back(field("samples.initial", "samples.initial", T::text, 0, 0, {"centre", "corners", "corners+centre"},
                    H::sample, "A cell's first samples", &BakeConfig::samples_initial));
  t.push_back(field("samples.void_threshold", "samples.void_threshold", T::number, 0, 1, {}, H::sample,
                    "Stop adding samples when the worst candidate's void is below this fraction of the sphere",
                    &BakeConfig::samples_void_threshold));
  t.push_back(field("samples.max", "samples.max", T::integer, 1, 64, {}, H::sample,
                    "Cap on samples per cell (initial set included)", &BakeConfig::samples_max));
  t.push_back(field("samples.void_resolution", "samples.void_resolution", T::integer, 4, 256, {}, H::sample,
                    "Void rays per candidate: this^2 per cube face", &BakeConfig::samples_void_resolution));
  t.push_back(field("samples.visibility_face_size", "samples.visibility_face_size", T::integer, 0, 4096, {}, H::sample,
                    "Face size of a cell's samples after its first when that one finds a far field drawn all as geometry: "
                    "they only find the triangles seen, without colour (0: none such; sample.face_size and above: "
                    "full size, the same rows)",
                    &BakeConfig::samples_visibility_face_size));
  t.push_back(field("samples.keep_margin_px", "samples.keep_margin_px", T::integer, 0, 16, {}, H::depth_mesh,
                    "Kept pixels of a delta scan grow this many rings back over removed ones",
                    &BakeConfig::samples_keep_margin_px));
  t.push_back(field("samples.min_island_px", "samples.min_island_px", T::integer, 0, kInt20, {}, H::depth_mesh,
                    "Kept specks of a delta scan smaller than this are dropped (before growing)",
                    &BakeConfig::samples_min_island_px));
  t.push_back(field("simplify.delta_boundary_error_px", "simplify.delta_boundary_error_px", T::number, 0, 8, {},
                    H::simplify, "simplify.boundary_error_px for delta scans (samples other than the root)",
                    &BakeConfig::delta_boundary_error_px));
  t.push_back(field("samples.redundancy_tolerance", "samples.redundancy_tolerance", T::number, 0, 0.1, {},
                    H::depth_mesh, "Relative inverse-depth agreement for \"an ancestor already holds this pixel\"",
                    &BakeConfig::samples_redundancy_tolerance));
  t.push_back(field("view.far_budget", "view.far_budget", T::integer, 0, kInt40, {}, H::none,
                    "What viewers draw: far-field triangles of the nearest sample and its ancestors, then more "
                    "samples while under this", &BakeConfig::far_budget));
  t.push_back(field("depth_mesh.skin_angle_deg", "depth_mesh.skin_angle_deg", T::number, 0, 45, {}, H::depth_mesh,
                    "Edges within this angle of the eye ray are skins", &BakeConfig::skin_angle_deg));
  t.push_back(field("depth_mesh.depth_jump", "depth_mesh.depth_jump", T::number, 1e-4, 10, {}, H::depth_mesh,
                    "Relative depth jump beyond which an edge is a skin", &BakeConfig::depth_jump));
  t.push_back(field("depth_mesh.multi_source_skins", "depth_mesh.multi_source_skins", T::text, 0, 0, {"on", "off"},
                    H::depth_mesh, "An edge is also a skin where another sample of the cell sees past its midpoint",
                    &BakeConfig::multi_source_skins));
  t.push_back(field("simplify.depth_error_relative", "simplify.depth_error_relative", T::number, 0, 1, {},
                    H::simplify, "Interior vertices move only along their eye ray, by at most this fraction of the depth",
                    &BakeConfig::depth_error_relative));
  t.push_back(field("simplify.boundary_error_px", "simplify.boundary_error_px", T::number, 0, 8, {}, H::simplify,
                    "Outlines move at most this far on screen (0: pixel-exact staircases)",
                    &BakeConfig::boundary_error_px));
  t.push_back(field("simplify.max_triangles", "simplify.max_triangles", T::integer, 2, kInt24, {}, H::simplify,
                    "Triangle cap per cube face (thesis VWALK cap)", &BakeConfig::max_face_triangles));
  t.push_back(field("encode.image_format", "encode.image_format", T::text, 0, 0, {"jpeg", "webp", "png", "avif", "jxl"},
                    H::encode, "Face image format (issue #16: avif is the measured best)", &BakeConfig::image_format));
  t.push_back(field("encode.quality", "encode.quality", T::integer, 1, 100, {}, H::encode,
                    "Quality of the lossy image formats", &BakeConfig::image_quality));
  t.push_back(field("encode.mesh_codec", "encode.mesh_codec", T::text, 0, 0, {"grid", "quantized"}, H::encode,
                    "Face meshes: pixel corners + log depth (grid, blob v2) or per-axis quantised positions "
                    "(quantized, blob v1)", &BakeConfig::mesh_codec));
  t.push_back(field("encode.mesh_depth_error", "encode.mesh_depth_error", T::number, 1e-6, 0.1, {}, H::encode,
                    "grid: the largest relative depth error the coding adds", &BakeConfig::mesh_depth_error));
  t.push_back(field("encode.position_bits", "encode.position_bits", T::integer, 8, 24, {}, H::encode,
                    "quantized: position bits per axis", &BakeConfig::position_bits));
  // Not in describe_bake_config.
  t.push_back(field("model.store", "", T::path, 0, 0, {}, H::none,
                    "The geometry store (its content hash enters the cell hashes, not its path)",
                    &BakeConfig::store));
  {
    BakeParameter floors{"cells.floors", "", T::floors, 0, double(1 << 20), {}, H::cell_grid,
                         "Floors found by `cellbake info` whose eye layers become the regions: \"all\" or indices "
                         "like [0, 2]", {}, {}};
    floors.get = [](const BakeConfig& c) -> ParameterValue { return floor_selection_text(c.floors); };
    floors.put = [](BakeConfig& c, const ParameterValue& v) {
      const std::string& s = std::get<std::string>(v);
      c.floors = s.empty() ? FloorSelection{} : parse_floor_selection(s, "cells.floors");
    };
    t.push_back(std::move(floors));
  }
  t.push_back(field("cells.eye_height", "", T::number, 0, 1e9, {}, H::cell_grid,
                    "Eyes this far above each selected floor (0: 1.7 m in the model's units)", &BakeConfig::eye_height));
  t.push_back(field("output.database", "", T::path, 0, 0, {}, H::none,
                    "The cell database written (relative: to the config file)", &BakeConfig::database));
  return t;
}

// Shortest round-trip text of a number (docs only; describe_bake_config keeps 17 digits).
std::string short_number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

const char* type_name(ParameterType t) {
  switch (t) {
    case T::integer: return "integer";
    case T::number: return "number";
    case T::text: return "string";
    case T::direction: return "[x, y, z]";
    case T::path: return "path";
    case T::floors: return "floors";
  }
  return "?";
}

std::string allowed_text(const BakeParameter& p) {
  switch (p.type) {
    case T::integer: return std::to_string(std::int64_t(p.lo)) + " .. " + std::to_string(std::int64_t(p.hi));
    case T::number: return short_number(p.lo) + " .. " + short_number(p.hi);
    case T::text: {
      if (p.allowed.empty()) return "any";
      std::string s;
      for (const auto& a : p.allowed) s += (s.empty() ? "" : ", ") + ("`" + a + "`");
      return s;
    }
    case T::direction: return "finite, not all 0";
    case T::path: return "a path";
    case T::floors: return "`\"all\"`, `\"none\"` or `[i, j, ...]`";
  }
  return "";
}

std::string doc_value_text(const ParameterValue& v) {
  if (const double* d = std::get_if<double>(&v)) return short_number(*d);
  if (const Vec3d* d = std::get_if<Vec3d>(&v))
    return "[" + short_number(d->x) + ", " + short_number(d->y) + ", " + short_number(d->z) + "]";
  if (const std::string* s = std::get_if<std::string>(&v)) return s->empty() ? "(none)" : "`" + *s + "`";
  return std::to_string(std::get<std::int64_t>(v));
}

}  // namespace

const char* hash_stage_name(HashStage stage) {
  switch (stage) {
    case H::none: return "none";
    case H::cell_grid: return "cell grid";
    case H::cull: return "cull";
    case H::sample: return "sample";
    case H::depth_mesh: return "depth_mesh";
    case H::simplify: return "simplify";
    case H::encode: return "encode";
    case H::far_choice: return "far_choice";
  }
  return "?";
}

const std::vector<BakeParameter>& bake_parameters() {
  static const std::vector<BakeParameter> table = make_table();
  return table;
}

const BakeParameter* find_bake_parameter(const std::string& key) {
  static const std::map<std::string, const BakeParameter*> index = [] {
    std::map<std::string, const BakeParameter*> m;
    for (const BakeParameter& p : bake_parameters()) m[p.key] = &p;
    return m;
  }();
  const auto it = index.find(key);
  return it == index.end() ? nullptr : it->second;
}

std::string parameter_value_text(const ParameterValue& value) {
  std::ostringstream o;
  o.precision(17);
  std::visit(
      [&](const auto& v) {
        if constexpr (std::is_same_v<std::decay_t<decltype(v)>, Vec3d>)
          o << v.x << "," << v.y << "," << v.z;
        else
          o << v;
      },
      value);
  return o.str();
}

std::string bake_parameters_markdown() {
  // Sections in order of first appearance, keys in table order within each.
  std::vector<std::string> sections;
  std::map<std::string, std::vector<const BakeParameter*>> by_section;
  for (const BakeParameter& p : bake_parameters()) {
    const std::string section = p.key.substr(0, p.key.find('.'));
    if (!by_section.count(section)) sections.push_back(section);
    by_section[section].push_back(&p);
  }
  const BakeConfig defaults;
  std::string s =
      "# Configuration\n\n"
      "<!-- Generated by `cellbake bake --list-parameters` from pipeline/bake_parameters.cpp; do not edit "
      "(tests/test_bake_parameters.cpp checks that this file is its output). -->\n\n"
      "A bake reads a TOML file (`cellbake bake FILE.toml`, e.g. configs/plant-demo.toml) with the sections "
      "below, plus `[[regions]]` tables of `min = [x, y, z]` and `max = [x, y, z]` (boxes of eye positions, model "
      "units); `--set section.key=value` overrides any key. Unknown keys and values out of range are errors naming "
      "the file and line.\n\n"
      "**Hash** is the stage of a cell's input hash the key enters (pipeline/cell_job.h `cell_hashes`): a resumed "
      "bake recomputes the cells whose hash changed. `cull` enters the cull-box hash and so every later one; "
      "`cell grid` keys decide which cells exist and their bounds, which are hashed; `none` keys change speed, "
      "memory, where output goes or what viewers draw, never a cell's rows.\n";
  for (const std::string& section : sections) {
    s += "\n## [" + section + "]\n\n| Key | Type | Allowed | Default | Hash | Meaning |\n|---|---|---|---|---|---|\n";
    for (const BakeParameter* p : by_section[section])
      s += "| `" + p->key + "` | " + type_name(p->type) + " | " + allowed_text(*p) + " | " +
           doc_value_text(p->get(defaults)) + " | " + hash_stage_name(p->hash) + " | " + p->doc + " |\n";
  }
  return s;
}

}  // namespace cellbake
