#include "pipeline/floor_regions.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>


namespace cellbake {
namespace {

std::string short_number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g", std::abs(v) < 5e-4 ? 0.0 : v);
  return buf;
}

// "3 floors: 0 at z = 0.02, 1 at z = 8, 2 at z = 16"
std::string list_floors(const std::vector<double>& heights, const char* axis) {
  std::string text = std::to_string(heights.size()) + (heights.size() == 1 ? " floor: " : " floors: ");
  for (std::size_t f = 0; f < heights.size(); ++f)
    text += (f ? ", " : "") + std::to_string(f) + " at " + axis + " = " + short_number(heights[f]);
  return text;
}

}  // namespace

double rounded_as_info_prints(double v, double cell_size) {
  // runner/info_report's region_step: hundredths, or three significant digits of a cell under 1.
  int digits = 2;
  if (cell_size > 0 && std::isfinite(cell_size))
    digits = std::max(2, 2 - int(std::floor(std::log10(cell_size))));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::min(digits, 12), v);
  return std::strtod(buf, nullptr) + 0.0;  // no -0
}

FloorRegions floor_regions(const std::vector<double>& heights, const FloorSelection& selection,
                           const std::vector<Box3d>& footprints, int up_axis, double eye_height,
                           const Box3d& model_bounds, double cell_size,
                           const std::vector<Box3d>& floor_footprints) {
  if (selection.empty()) throw std::invalid_argument("floor_regions: no floors selected");
  if (footprints.empty() && floor_footprints.size() != heights.size())
    throw std::invalid_argument("floor_regions: no footprint, and not one per floor");
  const char* axis = up_axis == 1 ? "y" : "z";
  FloorRegions out;
  out.heights = heights;
  if (heights.empty())
    throw std::runtime_error("floors " + floor_selection_text(selection) +
                             " asked for, but no floor was found (no wide upward-facing surface with headroom, as "
                             "`cellbake info` looks for them, up " + axis + "); give the eye heights as --region");
  std::vector<int> chosen;
  if (selection.all) {
    for (int f = 0; f < int(heights.size()); ++f) chosen.push_back(f);
  } else {
    for (int f : selection.indices)
      if (f < 0 || f >= int(heights.size()))
        throw std::runtime_error("floor " + std::to_string(f) + " asked for (floors " +
                                 floor_selection_text(selection) + "), but the model has " +
                                 list_floors(heights, axis) + " (as `cellbake info` finds them)");
    chosen = selection.indices;
  }
  for (int f : chosen) {
    const double eye = rounded_as_info_prints(heights[std::size_t(f)] + eye_height, cell_size);
    if (selection.all && !model_bounds.empty() && eye > model_bounds.hi[up_axis] + cell_size) {
      out.notes.push_back("floor " + std::to_string(f) + " at " + axis + " = " + short_number(heights[std::size_t(f)]) +
                          " left out: its eyes (" + axis + " = " + short_number(eye) +
                          ") are more than a cell above the model's top (" + short_number(model_bounds.hi[up_axis]) +
                          "); name it in --floors to bake it anyway with a larger cell size");
      continue;
    }
    const std::vector<Box3d> own{footprints.empty() ? floor_footprints[std::size_t(f)] : Box3d{}};
    for (const Box3d& footprint : footprints.empty() ? own : footprints) {
      FloorRegion r;
      r.floor = f;
      r.height = heights[std::size_t(f)];
      r.eye = eye;
      r.region = footprint;
      r.region.lo[up_axis] = r.region.hi[up_axis] = eye;
      out.regions.push_back(r);
    }
  }
  if (out.regions.empty())
    throw std::runtime_error("floors " + floor_selection_text(selection) + ": every floor was left out (" +
                             out.notes.front() + ")");
  return out;
}

ModelFloors find_model_floors(const ChunkSource& source, int up_axis) {
  ModelFloors m;
  FloorFinderParams params;
  params.up_axis = up_axis;
  m.found = find_floors(source, params);
  std::vector<double> heights;
  std::vector<std::uint64_t> rays;
  for (const Floor& f : m.found.floors) heights.push_back(f.height), rays.push_back(f.rays);
  m.units = units_from_storeys(heights, rays);
  if (!m.units.metres_plausible && !m.units.fitting.empty()) {
    m.unit = m.units.fitting.front();
    params.bin_size /= m.unit.metres;
    params.min_headroom /= m.unit.metres;
    params.min_separation /= m.unit.metres;
    m.found = find_floors(source, params);
  }
  return m;
}

FloorRegions find_floor_regions(const ChunkSource& source, const BakeConfig& config, const std::string& store_name) {
  const int up_axis = config.up == "y" ? 1 : 2;
  const ModelFloors floors = find_model_floors(source, up_axis);
  std::vector<double> heights;
  for (const Floor& f : floors.found.floors) heights.push_back(f.height);
  const double eye_height = config.eye_height > 0 ? config.eye_height : kEyeHeightMetres / floors.unit.metres;
  const Box3d bounds = source.model_bounds();
  std::vector<Box3d> walkable;  // used without configured regions: each floor's, as info suggests it
  for (const Floor& f : floors.found.floors) {
    Box3d b = walkable_extent(f);
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = rounded_as_info_prints(b.lo[a], config.cell_size);
      b.hi[a] = rounded_as_info_prints(b.hi[a], config.cell_size);
    }
    walkable.push_back(b);
  }
  try {
    FloorRegions r = floor_regions(heights, config.floors, config.regions, up_axis, eye_height, bounds,
                                   config.cell_size, walkable);
    r.eye_height = eye_height;
    r.unit = floors.unit;
    return r;
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(store_name + ": " + e.what());
  }
}

}  // namespace cellbake
