// Whole floors as bake regions (issue #36): `bake --floors all|0,2` and
// `[cells] floors` turn the floors `cellbake info` finds (stages/model_analysis/floor_finder.h,
// with the same parameters, so the indices are info's) into regions of eye
// positions before cell ids are given: per selected floor, per footprint (a
// configured region, or, when none is configured, the floor's own walkable
// extent, rounded as `info` prints its suggested region), the footprint's
// horizontal extent at one eye height `eye_height` above the floor — the
// layer a `--region X0,Y0,E,X1,Y1,E` gives. A floors bake therefore has
// exactly the cell ids and hashes of the equivalent `--region` bake, and the
// main floor's region is the one `info` suggests.
#pragma once

#include <string>
#include <vector>

#include "pipeline/bake_config.h"
#include "stages/chunk_source.h"
#include "stages/model_analysis/floor_finder.h"
#include "stages/geometry.h"
#include "stages/model_analysis/storey_units.h"

namespace cellbake {

struct FloorRegion {
  int floor = 0;      // index into the floors found (0 = the lowest)
  double height = 0;  // the floor's height along the up axis, model units
  double eye = 0;     // the eye layer: height + eye_height, rounded as info prints it
  Box3d region;       // the footprint's horizontal extent at `eye`
};

// The floors `cellbake info` reports: found with the finder's lengths in
// metres; when their storeys are no storeys in metres but are in other units
// (stages/model_analysis/storey_units.h), found again with the lengths (headroom, separation,
// bins) in the most typical of those, whose metres per unit `unit` then holds.
struct ModelFloors {
  FloorFinderResult found;
  StoreyUnits units;                 // what the first search's storeys say
  ModelUnit unit{"metres", 1};       // the units taken
};
ModelFloors find_model_floors(const ChunkSource& source, int up_axis);

// The default eye height above a floor: 1.7 m, in model units.
inline constexpr double kEyeHeightMetres = 1.7;

struct FloorRegions {
  std::vector<double> heights;       // every floor found, ascending
  double eye_height = 0;             // above each floor, model units (config.eye_height, or 1.7 m in `unit`)
  ModelUnit unit{"metres", 1};       // the units the floors were found in
  std::vector<FloorRegion> regions;  // floor by floor, then footprint by footprint: the bake's regions in order
  // Floors that "all" leaves out, one line each: an eye layer more than a cell
  // above the model's top (a roof), which the bake would refuse as a region.
  std::vector<std::string> notes;
};

// `v` (an eye height, a region's corner) rounded to the digits `cellbake info`
// prints a region's corners with at this cell size (hundredths, finer under a
// cell of 1): the double that reading that text back gives, so a typed
// --region matches it exactly.
double rounded_as_info_prints(double v, double cell_size);

// The regions for `selection` (not empty) of floors at `heights` (ascending),
// along `up_axis` (1: y, 2: z), over `footprints` — or, when `footprints` is
// empty, each floor over its own entry of `floor_footprints` (one per height).
// "all" leaves out a floor whose eye layer lies above model_bounds grown by
// one cell (with a note); a floor named by index is kept (the bake then says
// why it refuses it). Throws std::invalid_argument when neither footprint list
// fits, std::runtime_error naming the floors found when an index is not one of
// them, or when no floor was found.
FloorRegions floor_regions(const std::vector<double>& heights, const FloorSelection& selection,
                           const std::vector<Box3d>& footprints, int up_axis, double eye_height,
                           const Box3d& model_bounds, double cell_size,
                           const std::vector<Box3d>& floor_footprints = {});

// Finds the floors of `source` as `cellbake info` does (find_model_floors
// along config.up; reads every chunk once, twice for a model not in metres)
// and returns floor_regions for config.floors over config.regions (none: each
// floor's walkable extent, rounded as info prints it), eyes config.eye_height above the floors (0: 1.7 m in the
// units found). `store_name` names the store in messages.
FloorRegions find_floor_regions(const ChunkSource& source, const BakeConfig& config, const std::string& store_name);

}  // namespace cellbake
