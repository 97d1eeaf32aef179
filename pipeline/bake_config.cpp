#include "pipeline/bake_config.h"

#include "pipeline/bake_parameters.h"

#include <algorithm>
#include <cmath>
#include <toml++/toml.h>

#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

namespace cellbake {
namespace {

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

// Reads `n` as parameter `p` (type and range from the table) into `c`.
void set_parameter(BakeConfig& c, const BakeParameter& p, const toml::node& n, const std::string& w) {
  switch (p.type) {
    case ParameterType::integer:
      p.put(c, integer(n, w, p.key, std::int64_t(p.lo), std::int64_t(p.hi)));
      return;
    case ParameterType::number:
      p.put(c, number(n, w, p.key, p.lo, p.hi));
      return;
    case ParameterType::text:
      p.put(c, text(n, w, p.key, p.allowed));
      return;
    case ParameterType::direction:
      p.put(c, direction(n, w, p.key));
      return;
    case ParameterType::path:
      p.put(c, resolve(c, text(n, w, p.key), w).string());
      return;
    case ParameterType::floors: {
      if (const toml::array* a = n.as_array()) {
        std::string list;
        for (const auto& item : *a) {
          const std::int64_t f = integer(item, w, p.key, std::int64_t(p.lo), std::int64_t(p.hi));
          list += (list.empty() ? "" : ",") + std::to_string(f);
        }
        if (list.empty()) fail(w, "'" + p.key + "' = [] names no floor (\"all\", or indices like [0, 2])");
        p.put(c, floor_selection_text(parse_floor_selection(list, w + ": '" + p.key + "'")));
        return;
      }
      std::optional<std::string> v = n.value<std::string>();
      if (!v) fail(w, "'" + p.key + "' must be \"all\" or an array of floor indices like [0, 2]");
      p.put(c, floor_selection_text(parse_floor_selection(*v, w + ": '" + p.key + "'")));
      return;
    }
  }
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
      const BakeParameter* p = find_bake_parameter(full);
      if (!p) fail(where_of(file, v), "unknown key '" + full + "'");
      set_parameter(c, *p, v, where_of(file, v));
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
  const BakeParameter* p = find_bake_parameter(key);
  if (!p) throw std::runtime_error("--set '" + assignment + "': unknown key '" + key + "'");
  toml::table t;
  try {
    t = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    t = toml::table{{"v", value}};  // a bare word: take it as a string
  }
  set_parameter(c, *p, *t.get("v"), "--set " + key);
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
  for (const BakeParameter& p : bake_parameters())
    if (!p.described.empty()) o << p.described << "=" << parameter_value_text(p.get(c)) << "\n";
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
