// Which cells to measure before a long bake (`bake --dry-run --measure K`):
// a stratified sample, so that a few cells stand for the selection's mix of
// floors and of open and cluttered places. Strata are the regions (a floors
// bake has one per floor and footprint): each gets a share of K proportional
// to its cells (largest remainders; at least one each while K allows), and
// within a region the picks are evenly spaced along the Morton (Z-order) curve
// of the cells' grid indices, which spreads them over the grid.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "pipeline/cell_grid.h"

namespace cellbake {

// How many of `k` picks each stratum of the given sizes gets: at most its
// size, all of k (up to the total) handed out, at least one per stratum when
// k >= the strata count (else one each to k strata evenly spaced in order),
// the rest by largest remainder of size * k / total (ties: the earlier stratum).
std::vector<std::size_t> stratum_shares(const std::vector<std::size_t>& sizes, std::size_t k);

// Up to `k` of `cells` (all of them when k >= their count), chosen as above,
// in ascending id order. Deterministic.
std::vector<CellSpec> stratified_cells(const std::vector<CellSpec>& cells, std::size_t k);

}  // namespace cellbake
