#include "pipeline/cell_grid.h"

#include <cstdio>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cellbake {
namespace {

// Cells along one axis of a region; computed in double and checked before
// any integer conversion, so a huge or non-finite region is an error, not
// undefined behaviour.
constexpr double kMaxCellsAlongAxis = 1e7;

int cells_along(double extent, double size) {
  // Tolerate rounding: a 10 m region of 2 m cells is 5 cells, not 6.
  const double n = std::ceil(extent / size - 1e-9);
  if (!(n <= kMaxCellsAlongAxis))
    throw std::invalid_argument("a region " + std::to_string(extent) + " long holds more than " +
                                std::to_string(static_cast<long long>(kMaxCellsAlongAxis)) + " cells of size " +
                                std::to_string(size) + " along one axis (finite regions and a larger cell size, please)");
  return std::max(1, static_cast<int>(n));
}

}  // namespace

namespace {

struct RegionCells {
  int nx = 0, ny = 0, nz = 0;
  std::uint64_t count() const { return std::uint64_t(nx) * std::uint64_t(ny) * std::uint64_t(nz); }
};

void check_cell_size(double cell_size) {
  if (!(cell_size > 0) || !std::isfinite(cell_size)) throw std::invalid_argument("cell size must be positive");
}

// Every region's cell counts along x, y and z; throws when the total passes `max_cells`.
std::vector<RegionCells> region_cells(const std::vector<Box3d>& regions, double cell_size, std::uint64_t max_cells) {
  check_cell_size(cell_size);
  std::vector<RegionCells> out;
  std::uint64_t total = 0;
  for (const auto& r : regions) {
    if (!is_finite(r.lo) || !is_finite(r.hi)) throw std::invalid_argument("a region has a non-finite corner");
    const Vec3d e = r.extent();
    const RegionCells n{cells_along(e.x, cell_size), cells_along(e.y, cell_size), cells_along(e.z, cell_size)};
    const double count = double(n.nx) * n.ny * n.nz;
    if (count > double(max_cells))
      throw std::invalid_argument("regions hold more than " + std::to_string(max_cells) + " cells of size " +
                                  std::to_string(cell_size));
    total += n.count();
    if (total > max_cells)
      throw std::invalid_argument("regions hold more than " + std::to_string(max_cells) + " cells of size " +
                                  std::to_string(cell_size));
    out.push_back(n);
  }
  return out;
}

CellSpec make_cell(std::int64_t id, std::size_t region_index, const Box3d& r, double cell_size, int x, int y, int z) {
  const Vec3d e = r.extent();
  CellSpec c;
  c.id = id;
  c.region = static_cast<int>(region_index);
  c.gx = x;
  c.gy = y;
  c.gz = z;
  // A region thinner than a cell: centre the single layer on the region.
  Vec3d lo{r.lo.x + x * cell_size, r.lo.y + y * cell_size, r.lo.z + z * cell_size};
  for (int a = 0; a < 3; ++a)
    if (e[a] < cell_size) lo[a] = r.center()[a] - 0.5 * cell_size;
  c.bounds = {lo, lo + Vec3d{cell_size, cell_size, cell_size}};
  return c;
}

}  // namespace

std::vector<CellSpec> enumerate_cells(const std::vector<Box3d>& regions, double cell_size, std::uint64_t max_cells) {
  const std::vector<RegionCells> counts = region_cells(regions, cell_size, max_cells);
  std::uint64_t total = 0;
  for (const auto& n : counts) total += n.count();
  std::vector<CellSpec> cells;
  cells.reserve(total);
  std::int64_t id = 1;
  for (std::size_t ri = 0; ri < regions.size(); ++ri)
    for (int z = 0; z < counts[ri].nz; ++z)
      for (int y = 0; y < counts[ri].ny; ++y)
        for (int x = 0; x < counts[ri].nx; ++x) cells.push_back(make_cell(id++, ri, regions[ri], cell_size, x, y, z));
  return cells;
}

std::optional<CellSpec> cell_of_id(const std::vector<Box3d>& regions, double cell_size, std::int64_t id) {
  if (id < 1) return std::nullopt;
  const std::vector<RegionCells> counts = region_cells(regions, cell_size, 50'000'000);
  std::uint64_t k = std::uint64_t(id - 1);
  for (std::size_t ri = 0; ri < regions.size(); ++ri) {
    const RegionCells& n = counts[ri];
    if (k >= n.count()) {
      k -= n.count();
      continue;
    }
    const int x = int(k % std::uint64_t(n.nx)), y = int(k / std::uint64_t(n.nx) % std::uint64_t(n.ny)),
              z = int(k / (std::uint64_t(n.nx) * std::uint64_t(n.ny)));
    return make_cell(id, ri, regions[ri], cell_size, x, y, z);
  }
  return std::nullopt;
}

std::uint64_t count_cells(const std::vector<Box3d>& regions, double cell_size) {
  std::uint64_t total = 0;
  for (const auto& n : region_cells(regions, cell_size, 50'000'000)) total += n.count();
  return total;
}

std::vector<CellSpec> select_cells(const std::vector<CellSpec>& cells, const std::string& selection) {
  if (selection.empty()) return cells;
  std::vector<std::pair<std::int64_t, std::int64_t>> ranges;
  std::stringstream ss(selection);
  std::string part;
  while (std::getline(ss, part, ',')) {
    if (part.empty()) throw std::invalid_argument("--cells '" + selection + "': empty item");
    try {
      const auto dash = part.find('-');
      if (dash == std::string::npos) {
        const std::int64_t v = std::stoll(part);
        ranges.push_back({v, v});
      } else {
        const std::int64_t a = dash == 0 ? 1 : std::stoll(part.substr(0, dash));
        const std::int64_t b = dash + 1 == part.size() ? INT64_MAX : std::stoll(part.substr(dash + 1));
        if (a > b) throw std::invalid_argument("reversed range");
        ranges.push_back({a, b});
      }
    } catch (const std::exception&) {
      throw std::invalid_argument("--cells '" + selection + "': cannot parse '" + part + "' (use e.g. 1-10,15,20-)");
    }
  }
  std::vector<CellSpec> out;
  for (const auto& c : cells)
    for (const auto& [a, b] : ranges)
      if (c.id >= a && c.id <= b) {
        out.push_back(c);
        break;
      }
  if (out.empty() && !cells.empty()) {
    std::int64_t lo = cells.front().id, hi = cells.front().id;
    for (const auto& c : cells) lo = std::min(lo, c.id), hi = std::max(hi, c.id);
    throw std::invalid_argument("--cells '" + selection + "' selects none of the " + std::to_string(cells.size()) +
                                " cells (ids " + std::to_string(lo) + " to " + std::to_string(hi) + ")");
  }
  return out;
}

void check_regions_meet_model(const std::vector<Box3d>& regions, const Box3d& model, double cell_size) {
  if (model.empty()) return;
  const Box3d grown = Box3d{model.lo - Vec3d{cell_size, cell_size, cell_size}, model.hi + Vec3d{cell_size, cell_size, cell_size}};
  auto box_text = [](const Box3d& b) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%.10g,%.10g,%.10g .. %.10g,%.10g,%.10g", b.lo.x, b.lo.y, b.lo.z, b.hi.x,
                  b.hi.y, b.hi.z);
    return std::string(buf);
  };
  for (std::size_t i = 0; i < regions.size(); ++i)
    if (!regions[i].overlaps(grown))
      throw std::invalid_argument("region " + std::to_string(i + 1) + " (" + box_text(regions[i]) +
                                  ") does not meet the model's bounds (" + box_text(model) +
                                  ") grown by one cell; its cells would bake nothing nearby: move the region "
                                  "(`cellbake status STORE.db` shows the bounds)");
}

}  // namespace cellbake
