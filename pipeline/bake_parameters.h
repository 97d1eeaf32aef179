// The bake parameters as one declarative table: per key its TOML name, type,
// allowed range or values, the stage whose hash it enters and a one-line doc,
// with accessors into BakeConfig. The config parser and `--set`
// (pipeline/bake_config.cpp), describe_bake_config, `cellbake bake
// --list-parameters` and docs/configuration.md all read it; defaults are read
// from a default-constructed BakeConfig, so the struct stays their one source.
// tests/test_bake_parameters.cpp checks that every key enters exactly the cell
// hashes (pipeline/cell_job.h cell_hashes) its row says.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <variant>
#include <vector>

#include "pipeline/bake_config.h"

namespace cellbake {

enum class ParameterType {
  integer,    // a TOML integer in [lo, hi]
  number,     // a TOML number in [lo, hi]
  text,       // a TOML string, one of `allowed` (any when empty)
  direction,  // an array of 3 finite numbers, not all zero
  path,       // a string; relative paths resolve against the config file's folder
  floors,     // "all", "none" or an array of floor indices (parse_floor_selection)
};

// Which of cell_hashes' stages a key enters. `cull` enters CellHashes::cull
// (and so ::input too); the later stages enter ::input only.
enum class HashStage {
  none,        // by design no hash: speed, memory, output place, what viewers draw
  cell_grid,   // which cells exist and their bounds (the cell's bounds are hashed, not the key)
  cull,        // the cull box (the near field)
  sample,      // the panoramic samples: placement and pixels
  depth_mesh,  // the samples' depth meshes
  simplify,    // their simplification
  encode,      // images and mesh blobs
  far_choice,  // far geometry or depth meshes per face tile
};

const char* hash_stage_name(HashStage stage);

// A parameter's value: integers, numbers, strings (text, path, floors as
// floor_selection_text) or a direction.
using ParameterValue = std::variant<std::int64_t, double, std::string, Vec3d>;

struct BakeParameter {
  std::string key;          // "section.name" as in a config file and --set
  std::string described;    // its key in describe_bake_config ("" when not described)
  ParameterType type;
  double lo = 0, hi = 0;    // integer and number ranges
  std::vector<std::string> allowed;  // text: the allowed values (empty: any)
  HashStage hash;
  std::string doc;          // one line
  std::function<ParameterValue(const BakeConfig&)> get;
  // Stores an already validated value (the parser checks type and range).
  std::function<void(BakeConfig&, const ParameterValue&)> put;
};

// Every key, in describe_bake_config's order (keys it does not describe last).
const std::vector<BakeParameter>& bake_parameters();

// The row for `key`, or nullptr.
const BakeParameter* find_bake_parameter(const std::string& key);

// The value as describe_bake_config writes it (numbers with 17 digits,
// directions "x,y,z").
std::string parameter_value_text(const ParameterValue& value);

// The table as Markdown: docs/configuration.md is exactly this text.
std::string bake_parameters_markdown();

}  // namespace cellbake
