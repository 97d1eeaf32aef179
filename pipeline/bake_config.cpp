#include "pipeline/bake_config.h"

#include <algorithm>
#include <cmath>
#include <toml++/toml.h>

#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

namespace cellbake {
namespace {

using Setter = std::function<void(BakeConfig&, const toml::node&, const std::string& where)>;

std::string where_of(const std::string& file, const toml::node& n) {
  const auto& src = n.source();
  std::string w = file.empty() ? "<command line>" : file;
  if (src.begin.line > 0) w += ":" + std::to_string(src.begin.line);
  return w;
}

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::runtime_error(where + ": " + what);
}

double number(const toml::node& n, const std::string& where, const std::string& key, double lo, double hi) {
  std::optional<double> v = n.value<double>();
  if (!v) fail(where, "'" + key + "' must be a number");
  if (!(*v >= lo && *v <= hi))
    fail(where, "'" + key + "' = " + std::to_string(*v) + " is out of range [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
  return *v;
}

std::int64_t integer(const toml::node& n, const std::string& where, const std::string& key, std::int64_t lo,
                     std::int64_t hi) {
  std::optional<std::int64_t> v = n.value<std::int64_t>();
  if (!v || !n.is_integer()) fail(where, "'" + key + "' must be an integer");
  if (*v < lo || *v > hi)
    fail(where, "'" + key + "' = " + std::to_string(*v) + " is out of range [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
  return *v;
}

std::string text(const toml::node& n, const std::string& where, const std::string& key,
                 const std::vector<std::string>& allowed = {}) {
  std::optional<std::string> v = n.value<std::string>();
  if (!v) fail(where, "'" + key + "' must be a string");
  if (!allowed.empty()) {
    bool ok = false;
    std::string list;
    for (const auto& a : allowed) {
      ok |= (*v == a);
      list += (list.empty() ? "" : ", ") + a;
    }
    if (!ok) fail(where, "'" + key + "' = '" + *v + "' must be one of: " + list);
  }
  return *v;
}

Vec3d vec3(const toml::node& n, const std::string& where, const std::string& key) {
  const toml::array* a = n.as_array();
  if (!a || a->size() != 3) fail(where, "'" + key + "' must be an array of 3 numbers");
  Vec3d v;
  for (int i = 0; i < 3; ++i) {
    std::optional<double> d = (*a)[i].value<double>();
    if (!d || !std::isfinite(*d)) fail(where, "'" + key + "' must hold 3 finite numbers");
    v[i] = *d;
  }
  return v;
}

// A light direction: 3 finite numbers, not all zero (any length; normalised on use).
Vec3d direction(const toml::node& n, const std::string& where, const std::string& key) {
  const Vec3d v = vec3(n, where, key);
  if (!(length(v) > 0)) fail(where, "'" + key + "' must not be the zero vector");
  return v;
}

// A relative path written in a config file is relative to that file's folder;
// one given on the command line (`where` = "--set KEY", from apply_override)
// stays relative to the current directory, like --store and --out.
std::filesystem::path resolve(const BakeConfig& c, const std::string& p, const std::string& where = "") {
  std::filesystem::path path(p);
  const bool command_line = where.rfind("--set ", 0) == 0;
  if (path.is_relative() && !c.source.empty() && !command_line) path = c.source.parent_path() / path;
  return path;
}

const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> table = {
      {"model.store", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.store = resolve(c, text(n, w, "model.store"), w);
       }},
      {"model.up", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.up = text(n, w, "model.up", {"z", "y"});
         c.up_given = true;
       }},
      {"cells.size", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.cell_size = number(n, w, "cells.size", 1e-6, 1e9);
       }},
      {"cells.floors", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         if (const toml::array* a = n.as_array()) {
           std::string list;
           for (const auto& item : *a) {
             const std::int64_t f = integer(item, w, "cells.floors", 0, 1 << 20);
             list += (list.empty() ? "" : ",") + std::to_string(f);
           }
           if (list.empty()) fail(w, "'cells.floors' = [] names no floor (\"all\", or indices like [0, 2])");
           c.floors = parse_floor_selection(list, w + ": 'cells.floors'");
           return;
         }
         std::optional<std::string> v = n.value<std::string>();
         if (!v) fail(w, "'cells.floors' must be \"all\" or an array of floor indices like [0, 2]");
         c.floors = parse_floor_selection(*v, w + ": 'cells.floors'");
       }},
      {"cells.eye_height", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.eye_height = number(n, w, "cells.eye_height", 0, 1e9);  // 0: 1.7 m in the model's units
       }},
      {"near.budget", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.near_budget = static_cast<std::uint64_t>(integer(n, w, "near.budget", 0, std::int64_t(1) << 40));
       }},
      {"near.budget_fraction", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.near_budget_fraction = number(n, w, "near.budget_fraction", 0, 1);
       }},
      {"far.choice", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_choice = text(n, w, "far.choice", {"cheapest", "tdm", "geometry"});
       }},
      {"far.geometry_below", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_geometry_below = static_cast<std::uint64_t>(integer(n, w, "far.geometry_below", 0, std::int64_t(1) << 40));
       }},
      {"far.geometry_factor", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_geometry_factor = number(n, w, "far.geometry_factor", 0, 1e6);
       }},
      {"far.lod_error_px", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_lod_error_px = number(n, w, "far.lod_error_px", 0, 64);
       }},
      {"far.lod_replaces_exact", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_lod_replaces_exact = text(n, w, "far.lod_replaces_exact", {"on", "off", "auto"});
       }},
      {"far.seen_rings", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_seen_rings = int(integer(n, w, "far.seen_rings", 0, 8));
       }},
      {"sample.face_size", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.face_size = int(integer(n, w, "sample.face_size", 8, 4096));
       }},
      {"sample.supersample", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.supersample = int(integer(n, w, "sample.supersample", 1, 4));
       }},
      {"sample.near_plane", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.near_plane = number(n, w, "sample.near_plane", 1e-6, 1e3);
       }},
      {"sample.seam_shell_px", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.seam_shell_px = number(n, w, "sample.seam_shell_px", 0, 64);
       }},
      {"sample.backend", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.sample_backend = text(n, w, "sample.backend", {"osmesa", "egl", "embree", "auto"});
       }},
      {"sample.embree_cache_mb", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.embree_cache_mb = static_cast<std::uint64_t>(integer(n, w, "sample.embree_cache_mb", 64, std::int64_t(1) << 24));
       }},
      {"sample.texture_cache_mb", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.texture_cache_mb = static_cast<std::uint64_t>(integer(n, w, "sample.texture_cache_mb", 16, std::int64_t(1) << 24));
       }},
      {"shading.mode", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.shading.mode = parse_shading_mode(text(n, w, "shading.mode", {"lit", "unlit"}));
       }},
      {"shading.key_direction", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.shading.key_direction = direction(n, w, "shading.key_direction");
       }},
      {"shading.key_strength", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.shading.key_strength = number(n, w, "shading.key_strength", 0, 2);
       }},
      {"shading.fill_direction", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.shading.fill_direction = direction(n, w, "shading.fill_direction");
       }},
      {"shading.fill_strength", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.shading.fill_strength = number(n, w, "shading.fill_strength", 0, 2);
       }},
      {"shading.ambient", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.shading.ambient = number(n, w, "shading.ambient", 0, 2);
       }},
      {"samples.initial", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_initial = text(n, w, "samples.initial", {"centre", "corners", "corners+centre"});
       }},
      {"samples.void_threshold", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_void_threshold = number(n, w, "samples.void_threshold", 0, 1);
       }},
      {"samples.max", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_max = int(integer(n, w, "samples.max", 1, 64));
       }},
      {"samples.void_resolution", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_void_resolution = int(integer(n, w, "samples.void_resolution", 4, 256));
       }},
      {"samples.keep_margin_px", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_keep_margin_px = int(integer(n, w, "samples.keep_margin_px", 0, 16));
       }},
      {"samples.min_island_px", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_min_island_px = int(integer(n, w, "samples.min_island_px", 0, 1 << 20));
       }},
      {"simplify.delta_boundary_error_px", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.delta_boundary_error_px = number(n, w, "simplify.delta_boundary_error_px", 0, 8);
       }},
      {"samples.redundancy_tolerance", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.samples_redundancy_tolerance = number(n, w, "samples.redundancy_tolerance", 0, 0.1);
       }},
      {"view.far_budget", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.far_budget = static_cast<std::uint64_t>(integer(n, w, "view.far_budget", 0, std::int64_t(1) << 40));
       }},
      {"depth_mesh.skin_angle_deg", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.skin_angle_deg = number(n, w, "depth_mesh.skin_angle_deg", 0, 45);
       }},
      {"depth_mesh.depth_jump", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.depth_jump = number(n, w, "depth_mesh.depth_jump", 1e-4, 10);
       }},
      {"depth_mesh.multi_source_skins", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.multi_source_skins = text(n, w, "depth_mesh.multi_source_skins", {"on", "off"});
       }},
      {"simplify.depth_error_relative", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.depth_error_relative = number(n, w, "simplify.depth_error_relative", 0, 1);
       }},
      {"simplify.boundary_error_px", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.boundary_error_px = number(n, w, "simplify.boundary_error_px", 0, 8);
       }},
      {"simplify.max_triangles", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.max_face_triangles = int(integer(n, w, "simplify.max_triangles", 2, 1 << 24));
       }},
      {"encode.image_format", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.image_format = text(n, w, "encode.image_format", {"jpeg", "webp", "png", "avif", "jxl"});
       }},
      {"encode.quality", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.image_quality = int(integer(n, w, "encode.quality", 1, 100));
       }},
      {"encode.mesh_codec", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.mesh_codec = text(n, w, "encode.mesh_codec", {"grid", "quantized"});
       }},
      {"encode.mesh_depth_error", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.mesh_depth_error = number(n, w, "encode.mesh_depth_error", 1e-6, 0.1);
       }},
      {"encode.position_bits", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.position_bits = int(integer(n, w, "encode.position_bits", 8, 24));
       }},
      {"output.database", [](BakeConfig& c, const toml::node& n, const std::string& w) {
         c.database = resolve(c, text(n, w, "output.database"), w);
       }},
  };
  return table;
}

Box3d parse_region(const toml::table& t, const std::string& file) {
  Box3d box;
  bool has_min = false, has_max = false;
  for (const auto& [k, v] : t) {
    const std::string key(k.str());
    const std::string w = where_of(file, v);
    if (key == "min") {
      box.lo = vec3(v, w, "regions.min");
      has_min = true;
    } else if (key == "max") {
      box.hi = vec3(v, w, "regions.max");
      has_max = true;
    } else {
      fail(w, "unknown key 'regions." + key + "' (expected min, max)");
    }
  }
  const std::string w = where_of(file, t);
  if (!has_min || !has_max) fail(w, "a region needs both 'min' and 'max'");
  if (box.lo.x > box.hi.x || box.lo.y > box.hi.y || box.lo.z > box.hi.z)
    fail(w, "region 'min' must be <= 'max' on every axis");
  return box;
}

void apply_table(BakeConfig& c, const toml::table& root, const std::string& file) {
  for (const auto& [section_key, section] : root) {
    const std::string section_name(section_key.str());
    const std::string w = where_of(file, section);
    if (section_name == "regions") {
      const toml::array* arr = section.as_array();
      if (!arr) fail(w, "'regions' must be an array of tables ([[regions]])");
      c.regions.clear();
      for (const auto& r : *arr) {
        const toml::table* t = r.as_table();
        if (!t) fail(where_of(file, r), "each region must be a table with min and max");
        c.regions.push_back(parse_region(*t, file));
      }
      continue;
    }
    const toml::table* t = section.as_table();
    if (!t) fail(w, "unknown top-level key '" + section_name + "'");
    for (const auto& [k, v] : *t) {
      const std::string full = section_name + "." + std::string(k.str());
      auto it = setters().find(full);
      if (it == setters().end()) fail(where_of(file, v), "unknown key '" + full + "'");
      it->second(c, v, where_of(file, v));
    }
  }
}

BakeConfig config_from_table(const toml::table& root, const std::filesystem::path& file) {
  BakeConfig c;
  c.source = file;
  c.database = "";
  apply_table(c, root, file.string());
  if (c.database.empty()) c.database = resolve(c, "cells.db");
  return c;
}

}  // namespace

BakeConfig load_bake_config(const std::filesystem::path& file) {
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(file.string() + ":" + std::to_string(e.source().begin.line) + ": " +
                             std::string(e.description()));
  }
  return config_from_table(root, file);
}

BakeConfig parse_bake_config(std::string_view text, const std::filesystem::path& file) {
  toml::table root;
  try {
    root = toml::parse(text, file.string());
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(file.string() + ":" + std::to_string(e.source().begin.line) + ": " +
                             std::string(e.description()));
  }
  return config_from_table(root, file);
}

void apply_override(BakeConfig& c, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) throw std::runtime_error("--set '" + assignment + "': expected section.key=value");
  const std::string key = assignment.substr(0, eq);
  std::string value = assignment.substr(eq + 1);
  auto it = setters().find(key);
  if (it == setters().end()) throw std::runtime_error("--set '" + assignment + "': unknown key '" + key + "'");
  toml::table t;
  try {
    t = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    t = toml::table{{"v", value}};  // a bare word: take it as a string
  }
  it->second(c, *t.get("v"), "--set " + key);
}

std::uint64_t effective_near_budget(const BakeConfig& c, std::uint64_t model_triangles) {
  if (c.near_budget_fraction <= 0) return c.near_budget;
  constexpr double kFloor = 4096;  // one chunk (stages/chunking.h)
  const double scaled = std::max(kFloor, std::ceil(c.near_budget_fraction * double(model_triangles)));
  return std::min(c.near_budget, static_cast<std::uint64_t>(scaled));
}

FloorSelection parse_floor_selection(const std::string& text, const std::string& what) {
  FloorSelection s;
  if (text == "all") {
    s.all = true;
    return s;
  }
  if (text == "none") return s;  // overrides a configuration's floors: its regions as given
  std::stringstream in(text);
  for (std::string word; std::getline(in, word, ',');) {
    const std::size_t a = word.find_first_not_of(" \t"), b = word.find_last_not_of(" \t");
    word = a == std::string::npos ? "" : word.substr(a, b - a + 1);
    const bool digits = !word.empty() && word.size() <= 7 && word.find_first_not_of("0123456789") == std::string::npos;
    if (!digits)
      throw std::runtime_error(what + " '" + text + "': '" + word +
                               "' is not a floor index (expected \"all\" or indices like 0,2; 0 = the lowest floor)");
    s.indices.push_back(std::stoi(word));
  }
  if (s.indices.empty())
    throw std::runtime_error(what + " '" + text + "': no floor named (expected \"all\" or indices like 0,2)");
  std::sort(s.indices.begin(), s.indices.end());
  s.indices.erase(std::unique(s.indices.begin(), s.indices.end()), s.indices.end());
  return s;
}

std::string floor_selection_text(const FloorSelection& s) {
  if (s.all) return "all";
  std::string text;
  for (int f : s.indices) text += (text.empty() ? "" : ",") + std::to_string(f);
  return text;
}

void validate_bake_config(const BakeConfig& c) {
  const std::string where = c.source.empty() ? "<command line>" : c.source.string();
  if (c.store.empty()) throw std::runtime_error(where + ": no geometry store given ([model] store or --store)");
  if (c.regions.empty() && c.floors.empty())
    throw std::runtime_error(where + ": no regions given ([[regions]], --region, or floors: [cells] floors, --floors)");
  if (c.database.empty()) throw std::runtime_error(where + ": no output database given");
}

std::string resolve_up_axis(BakeConfig& c, const std::string& store_up, const std::string& store_up_source) {
  const std::string why = store_up_source.empty() ? "" : " (" + store_up_source + ")";
  if (c.up_given) {
    if (!store_up.empty() && store_up != c.up)
      return "warning: the bake's up axis is " + c.up + " but the geometry store records " + store_up + why +
             "; cell layers stack along " + c.up;
    return "";
  }
  if (store_up.empty()) {
    c.up = "z";
    return "note: up axis not recorded in the store; assuming z (--up y to change)";
  }
  c.up = store_up;
  return "";
}

std::string describe_bake_config(const BakeConfig& c) {
  std::ostringstream o;
  o.precision(17);
  o << "up=" << c.up << "\ncells.size=" << c.cell_size << "\nnear.budget=" << c.near_budget
    << "\nnear.budget_fraction=" << c.near_budget_fraction << "\nfar.choice=" << c.far_choice
    << "\nfar.geometry_below=" << c.far_geometry_below << "\nfar.seen_rings=" << c.far_seen_rings
    << "\nfar.lod_error_px=" << c.far_lod_error_px << "\nfar.lod_replaces_exact=" << c.far_lod_replaces_exact
    << "\nfar.geometry_factor=" << c.far_geometry_factor
    << "\nsample.face_size=" << c.face_size << "\nsample.supersample=" << c.supersample
    << "\nsample.near_plane=" << c.near_plane << "\nsample.seam_shell_px=" << c.seam_shell_px
    << "\nsample.backend=" << c.sample_backend << "\nsample.embree_cache_mb=" << c.embree_cache_mb
    << "\nsample.texture_cache_mb=" << c.texture_cache_mb
    << "\nshading.mode=" << shading_mode_name(c.shading.mode) << "\nshading.key_direction=" << c.shading.key_direction.x
    << "," << c.shading.key_direction.y << "," << c.shading.key_direction.z
    << "\nshading.key_strength=" << c.shading.key_strength << "\nshading.fill_direction=" << c.shading.fill_direction.x
    << "," << c.shading.fill_direction.y << "," << c.shading.fill_direction.z
    << "\nshading.fill_strength=" << c.shading.fill_strength << "\nshading.ambient=" << c.shading.ambient
    << "\nsamples.initial=" << c.samples_initial
    << "\nsamples.void_threshold=" << c.samples_void_threshold << "\nsamples.max=" << c.samples_max << "\nsamples.void_resolution=" << c.samples_void_resolution << "\nsamples.keep_margin_px=" << c.samples_keep_margin_px << "\nsamples.min_island_px=" << c.samples_min_island_px
    << "\nsimplify.delta_boundary_error_px=" << c.delta_boundary_error_px
    << "\nsamples.redundancy_tolerance=" << c.samples_redundancy_tolerance << "\nview.far_budget=" << c.far_budget
    << "\ndepth_mesh.skin_angle_deg=" << c.skin_angle_deg
    << "\ndepth_mesh.depth_jump=" << c.depth_jump << "\ndepth_mesh.multi_source_skins=" << c.multi_source_skins
    << "\nsimplify.depth_error_relative=" << c.depth_error_relative
    << "\nsimplify.boundary_error_px=" << c.boundary_error_px << "\nsimplify.max_triangles=" << c.max_face_triangles << "\nencode.image_format=" << c.image_format
    << "\nencode.quality=" << c.image_quality << "\nencode.mesh_codec=" << c.mesh_codec
    << "\nencode.mesh_depth_error=" << c.mesh_depth_error << "\nencode.position_bits=" << c.position_bits << "\n";
  for (const auto& r : c.regions)
    o << "region=" << r.lo.x << "," << r.lo.y << "," << r.lo.z << "," << r.hi.x << "," << r.hi.y << "," << r.hi.z
      << "\n";
  return o.str();
}

DescribedConfig config_from_description(const std::string& text) {
  DescribedConfig out;
  out.config.database = "";
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    const std::size_t eq = line.find('=');
    const std::string key = line.substr(0, eq), value = eq == std::string::npos ? "" : line.substr(eq + 1);
    try {
      if (eq == std::string::npos) throw std::runtime_error("not a key=value line");
      if (key == "region") {
        double v[6];
        std::istringstream values(value);
        char comma = ',';
        for (int i = 0; i < 6; ++i)
          if ((i > 0 && !(values >> comma)) || comma != ',' || !(values >> v[i]) || !std::isfinite(v[i]))
            throw std::runtime_error("'" + value + "' is not six finite numbers");
        if (!(values >> std::ws).eof()) throw std::runtime_error("'" + value + "' is not six finite numbers");
        const Box3d r{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
        if (r.lo.x > r.hi.x || r.lo.y > r.hi.y || r.lo.z > r.hi.z)
          throw std::runtime_error("'" + value + "': min must be <= max on every axis");
        out.config.regions.push_back(r);
        continue;
      }
      // Directions are written bare ("x,y,z"); as an override they are a TOML array.
      const bool vector = key == "shading.key_direction" || key == "shading.fill_direction";
      apply_override(out.config, (key == "up" ? std::string("model.up") : key) + "=" +
                                     (vector ? "[" + value + "]" : value));
    } catch (const std::exception& e) {
      std::string what = e.what();
      for (const std::string& prefix : {"--set " + (key == "up" ? std::string("model.up") : key) + ": ", std::string("--set ")})
        if (what.rfind(prefix, 0) == 0) {
          what = what.substr(prefix.size());
          break;
        }
      out.problems.push_back(key + ": " + what);
    }
  }
  return out;
}

}  // namespace cellbake
