// The parameter table (pipeline/bake_parameters.h) against what reads it:
// every key enters exactly the cell hashes its row says, the parser and
// describe_bake_config cover the same keys, docs/configuration.md is the
// table's Markdown.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "pipeline/bake_config.h"
#include "pipeline/bake_parameters.h"
#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"

namespace cellbake {
namespace {

// The hashes of `cell` under `config` as the bake computes them (bake_runner
// replaces near.budget with the effective budget first), for a model where
// near.budget_fraction sets that budget (0.5 M triangles) and one where
// near.budget does (5 M), joined.
CellHashes hashes_of(const CellSpec& cell, const BakeConfig& config) {
  CellHashes joined;
  for (std::uint64_t model_triangles : {500000u, 5000000u}) {
    BakeConfig c = config;
    c.near_budget = effective_near_budget(config, model_triangles);
    const CellHashes h = cell_hashes(cell, c, "store");
    joined.cull += h.cull + " ";
    joined.input += h.input + " ";
  }
  return joined;
}

// Valid values other than the default to try for `p`.
std::vector<ParameterValue> other_values(const BakeParameter& p, const ParameterValue& dflt) {
  std::vector<ParameterValue> out;
  switch (p.type) {
    case ParameterType::integer: {
      const std::int64_t d = std::get<std::int64_t>(dflt);
      for (std::int64_t v : {std::int64_t(p.lo), std::int64_t(p.hi), d + 1, d - 1})
        if (v >= std::int64_t(p.lo) && v <= std::int64_t(p.hi) && v != d) out.push_back(v);
      break;
    }
    case ParameterType::number: {
      const double d = std::get<double>(dflt);
      for (double v : {p.lo, p.hi, d * 1.5, d * 0.5})
        if (v >= p.lo && v <= p.hi && v != d) out.push_back(v);
      break;
    }
    case ParameterType::text:
      for (const std::string& v : p.allowed)
        if (v != std::get<std::string>(dflt)) out.push_back(v);
      break;
    case ParameterType::direction:
      for (Vec3d v : {Vec3d{1, 0, 0}, Vec3d{0, -1, 0.5}})
        if (parameter_value_text(v) != parameter_value_text(dflt)) out.push_back(v);
      break;
    case ParameterType::path: out.push_back(std::string("elsewhere/other.file")); break;
    case ParameterType::floors:
      out.push_back(std::string("all"));
      out.push_back(std::string("0,2"));
      break;
  }
  return out;
}

TEST(BakeParameters, EveryKeyEntersExactlyTheHashesItsRowSays) {
  BakeConfig base;
  base.regions = {Box3d{{0, 0, 0}, {4, 4, 2}}};
  const CellSpec cell = enumerate_cells(base.regions, base.cell_size).front();
  const CellHashes before = hashes_of(cell, base);
  for (const BakeParameter& p : bake_parameters()) {
    const ParameterValue dflt = p.get(base);
    const std::vector<ParameterValue> values = other_values(p, dflt);
    ASSERT_FALSE(values.empty()) << p.key;
    bool changed = false;
    for (const ParameterValue& v : values) {
      BakeConfig c = base;
      p.put(c, v);
      ASSERT_EQ(parameter_value_text(p.get(c)), parameter_value_text(v)) << p.key << ": put then get";
      const CellHashes after = hashes_of(cell, c);
      const std::string what = p.key + "=" + parameter_value_text(v) + " (hash: " + hash_stage_name(p.hash) + ")";
      switch (p.hash) {
        case HashStage::none:
        case HashStage::cell_grid:  // enters through the cell's bounds, fixed here
          EXPECT_EQ(after.cull, before.cull) << what;
          EXPECT_EQ(after.input, before.input) << what;
          break;
        case HashStage::cull:
          EXPECT_NE(after.cull, before.cull) << what;
          EXPECT_NE(after.input, before.input) << what;
          changed = true;
          break;
        default:  // a later stage: the input hash only
          EXPECT_EQ(after.cull, before.cull) << what;
          // Numbers and directions change it with every value; of a string's
          // values some may draw alike (sample.backend osmesa and egl are
          // both GL pixels), so one changing it is enough.
          if (p.type != ParameterType::text) {
            EXPECT_NE(after.input, before.input) << what;
          }
          changed |= after.input != before.input;
          break;
      }
    }
    if (p.hash != HashStage::none && p.hash != HashStage::cell_grid) {
      EXPECT_TRUE(changed) << p.key << " changes no hash though its row says " << hash_stage_name(p.hash);
    }
  }
}

TEST(BakeParameters, TheDefaultConfigHashesAsBefore) {
  // Existing databases resume only while keys at their defaults hash as they
  // did: the default configuration's hashes as of issue #36 (samples.max 8,
  // far.seen_rings 4, samples.void_resolution 12: the input hash changed on
  // purpose; the cull hash did not).
  BakeConfig c;
  c.regions = {Box3d{{0, 0, 0}, {4, 4, 2}}};
  const CellHashes h = cell_hashes(enumerate_cells(c.regions, c.cell_size).front(), c, "store");
  EXPECT_EQ(h.cull, "05729ed4ba2b0461d9726fbd997f6b5f");
  EXPECT_EQ(h.input, "e66449d0166d202ce30f5bb0988067d9");
}

TEST(BakeParameters, CellGridKeysMoveTheCellsWhoseBoundsAreHashed) {
  BakeConfig a;
  a.regions = {Box3d{{0, 0, 0}, {4, 4, 2}}};
  BakeConfig b = a;
  find_bake_parameter("cells.size")->put(b, 3.0);
  const CellSpec ca = enumerate_cells(a.regions, a.cell_size).front();
  const CellSpec cb = enumerate_cells(b.regions, b.cell_size).front();
  EXPECT_NE(cell_hashes(ca, a, "store").cull, cell_hashes(cb, b, "store").cull);
}

TEST(BakeParameters, TheParserAndTheDescriptionCoverTheTable) {
  BakeConfig c;
  std::set<std::string> described;
  std::istringstream in(describe_bake_config(c));
  for (std::string line; std::getline(in, line);) described.insert(line.substr(0, line.find('=')));
  for (const BakeParameter& p : bake_parameters()) {
    // Every key is accepted by --set with its default value written back.
    const ParameterValue v = p.get(c);
    std::string text = parameter_value_text(v);
    if (p.type == ParameterType::direction) text = "[" + text + "]";
    if (p.type == ParameterType::path && text.empty()) text = "x";
    if (p.type == ParameterType::floors) text = "\"all\"";
    BakeConfig d;
    EXPECT_NO_THROW(apply_override(d, p.key + "=" + text)) << p.key;
    if (!p.described.empty()) {
      EXPECT_TRUE(described.count(p.described)) << p.key;
    }
    if (p.type == ParameterType::integer || p.type == ParameterType::number) {
      BakeConfig e;
      std::ostringstream above;
      above.precision(17);
      above << p.hi * 2 + 1;
      EXPECT_THROW(apply_override(e, p.key + "=" + (p.type == ParameterType::integer
                                                         ? std::to_string(std::int64_t(p.hi) + 1)
                                                         : above.str())),
                   std::runtime_error)
          << p.key;
    }
  }
  EXPECT_THROW(apply_override(c, "far.no_such_key=1"), std::runtime_error);
  // The description's keys are the table's described keys, in its order.
  std::size_t n = 0;
  for (const BakeParameter& p : bake_parameters()) n += !p.described.empty();
  EXPECT_EQ(described.size(), n);
}

TEST(BakeParameters, DocsConfigurationIsTheGeneratedTable) {
  const std::filesystem::path file = std::filesystem::path(CELLBAKE_SOURCE_DIR) / "docs" / "configuration.md";
  std::ifstream in(file, std::ios::binary);
  ASSERT_TRUE(in) << file;
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), bake_parameters_markdown())
      << "docs/configuration.md is out of date: cellbake bake --list-parameters > docs/configuration.md";
}

}  // namespace
}  // namespace cellbake
