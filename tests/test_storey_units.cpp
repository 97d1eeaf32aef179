// Model units from storey heights (issue #38 item 5): the storeys' median gap
// with analytic answers (metres plausible, centimetres or inches, nothing
// fits, minor floors left out), and `cellbake info` on the first-hour house
// written in centimetres: units suggested, floors found again in them, eye
// height 170 above the floor and 200-unit cells (2 m, a person's choice).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "stages/model_analysis/storey_units.h"
#include "tests/fixture_house_model.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

TEST(StoreyUnits, MetresWhenTheStoreysArePlausibleInMetres) {
  const StoreyUnits plant = units_from_storeys({0, 8, 16}, {900, 800, 700});
  EXPECT_DOUBLE_EQ(plant.storey, 8);
  EXPECT_TRUE(plant.metres_plausible);
  EXPECT_TRUE(plant.fitting.empty());
  // One floor, or none: nothing measured, metres kept.
  EXPECT_TRUE(units_from_storeys({0}, {10}).metres_plausible);
  EXPECT_EQ(units_from_storeys({}, {}).storey, 0);
  EXPECT_THROW(units_from_storeys({0, 3}, {1}), std::invalid_argument);
}

TEST(StoreyUnits, HundredsOfUnitsApartAreCentimetresOrInches) {
  // 256 and 288 between storeys (median 272): 2.72 m in centimetres, 6.91 m in inches; centimetres nearer 3.5 m.
  const StoreyUnits u = units_from_storeys({0, 256, 544}, {100, 90, 80});
  EXPECT_DOUBLE_EQ(u.storey, 272);
  EXPECT_FALSE(u.metres_plausible);
  ASSERT_EQ(u.fitting.size(), 2u);
  EXPECT_EQ(u.fitting[0].name, "centimetres");
  EXPECT_DOUBLE_EQ(u.fitting[0].metres, 0.01);
  EXPECT_EQ(u.fitting[1].name, "inches");
  EXPECT_NE(u.evidence.find("centimetres (2.72 m) or inches (6.91 m)"), std::string::npos) << u.evidence;
  // 3000 apart: millimetres alone; 11 apart: feet alone (3.35 m).
  const StoreyUnits mm = units_from_storeys({0, 3000}, {5, 5});
  ASSERT_EQ(mm.fitting.size(), 1u);
  EXPECT_EQ(mm.fitting[0].name, "millimetres");
  const StoreyUnits ft = units_from_storeys({0, 11}, {5, 5});
  ASSERT_EQ(ft.fitting.size(), 1u);
  EXPECT_EQ(ft.fitting[0].name, "feet");
  // 1.2 apart fits no unit: nothing suggested.
  const StoreyUnits none = units_from_storeys({0, 1.2}, {5, 5});
  EXPECT_FALSE(none.metres_plausible);
  EXPECT_TRUE(none.fitting.empty());
}

TEST(StoreyUnits, MinorFloorsDoNotMakeStoreys) {
  // Table tops at 75 and 375 hit by few rays: the main floors 0, 300, 600 set the storey.
  const StoreyUnits u = units_from_storeys({0, 75, 300, 375, 600}, {1000, 40, 900, 40, 950});
  EXPECT_DOUBLE_EQ(u.storey, 300);
  ASSERT_FALSE(u.fitting.empty());
  EXPECT_EQ(u.fitting[0].name, "centimetres");
}

TEST(StoreyUnits, InfoOnAHouseInCentimetresScalesEyeHeightAndCellSize) {
  test::TempDir dir;
  std::vector<test::HouseTriangle> house = test::house_triangles();
  for (auto& t : house)
    for (Vec3d& p : t) p = p * 100.0;
  const auto obj = dir / "house_cm.obj";
  std::ofstream(obj, std::ios::binary) << test::triangles_obj(house);
  const auto r = test::run_cellbake("info --json '" + obj.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto doc = nlohmann::json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(doc["up_used"], "z");
  EXPECT_EQ(doc["units"]["taken_as"], "centimetres") << doc["units"].dump();
  EXPECT_DOUBLE_EQ(doc["units"]["storey"].get<double>(), 300) << doc["floors"].dump();
  const auto& s = doc["suggested"];
  EXPECT_NEAR(s["floor"].get<double>(), 0, 5);
  EXPECT_NEAR(s["eye_height"].get<double>(), s["floor"].get<double>() + 170, 1e-9);
  const double cell = s["cell_size"];
  EXPECT_GE(cell, 100);  // within 2x of a person's 1-4 m
  EXPECT_LE(cell, 400);
  EXPECT_LE(s["cells"].get<int>(), 200) << s.dump();
  const auto text = test::run_cellbake("info '" + obj.string() + "'");
  EXPECT_NE(text.output.find("model units taken as centimetres"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("centimetres (3.00 m) or inches (7.62 m)"), std::string::npos) << text.output;
  // The same house in metres says nothing about units.
  const auto metres = dir / "house.obj";
  std::ofstream(metres, std::ios::binary) << test::triangles_obj(test::house_triangles());
  const auto m = test::run_cellbake("info --json '" + metres.string() + "'");
  const auto mdoc = nlohmann::json::parse(m.output.substr(m.output.find('{')));
  EXPECT_EQ(mdoc["units"]["taken_as"], "metres");
  EXPECT_TRUE(mdoc["units"]["metres_plausible"].get<bool>());
}

}  // namespace
}  // namespace cellbake
