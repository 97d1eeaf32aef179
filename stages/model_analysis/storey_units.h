// Model units from storey heights (issue #38 item 5). cellbake takes model
// units as metres (eye height 1.7, cells of 2-4, a floor needs 1.9 of
// headroom); a model in centimetres, inches or a game's units has its storeys
// hundreds of units apart. Building storeys are about 2.4-8.5 m apart (homes
// 2.5-3 m, plants and halls up to 8 m), so the gap between a model's main
// floors says which units are plausible: 264 units is no storey in metres but
// is one in centimetres (2.64 m) or inches (6.7 m). Pure; deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace cellbake {

struct StoreyUnitsParams {
  double min_storey_m = 2.4;  // a plausible storey height, metres
  double max_storey_m = 8.5;
  double typical_storey_m = 3.5;  // of several fitting units, the one nearest this (in ratio) comes first
  double main_share = 0.25;  // main floors: hit by at least this share of the rays of the most-hit floor
};

struct ModelUnit {
  std::string name;   // "centimetres"
  double metres = 1;  // one model unit in metres
};

struct StoreyUnits {
  double storey = 0;  // median gap between consecutive main floors, model units (0: fewer than 2 main floors)
  bool metres_plausible = true;  // the storey taken as metres is plausible (or nothing was measured)
  std::vector<ModelUnit> fitting;  // when not: the units in which it is (centimetres, inches, millimetres, feet), most typical first
  std::string evidence;            // one line for people ("" when nothing was measured)
};

// The units the floors at `heights` (ascending, model units) suggest, the
// floors weighted by `rays` (how many rays hit each; same length).
StoreyUnits units_from_storeys(const std::vector<double>& heights, const std::vector<std::uint64_t>& rays,
                               const StoreyUnitsParams& params = {});

}  // namespace cellbake
