// Speed against error as a curve: `cellbake verify --far-budget-sweep B1,B2,...`
// draws every random view once more per far-field budget (viewer/
// sample_selection.h: the nearest sample with its ancestors, then more
// samples while the far field's triangles stay under the budget) and records
// the triangles drawn and the PSNR against the truth. This file holds the
// per-view record, the summary per budget (medians over the views) and its
// report forms (a plot of median PSNR against median triangles drawn, with
// the truth's frustum-culled count for scale, and an HTML table). Pure code.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runner/verify/svg_plot.h"

namespace cellbake {

// One view drawn under one far budget.
struct FarBudgetPoint {
  std::uint64_t far_budget = 0;
  std::uint64_t triangles = 0;  // near field + far geometry + depth meshes drawn
  double psnr_db = 0;           // against the truth; +infinity when identical
};

// One budget over all views that were drawn under it.
struct FarBudgetSummary {
  std::uint64_t far_budget = 0;
  std::size_t views = 0;
  double triangles_median = 0;
  double psnr_median_db = 0;  // +infinity when most views are identical
  double psnr_worst_db = 0;
};

// Parses "25000,50000,100000" (ascending or not; duplicates dropped; result
// ascending). Throws std::invalid_argument naming the bad item for an empty
// item, a non-integer or zero.
std::vector<std::uint64_t> parse_far_budget_sweep(const std::string& text);

// Per budget (ascending), the medians and the worst PSNR over the points of
// every view in `views` (each view's points in any order; a view without a
// point for a budget does not count for it). Deterministic.
std::vector<FarBudgetSummary> summarise_far_budget_sweep(
    const std::vector<std::vector<FarBudgetPoint>>& views);

// The curve as a plot: one point per budget (x = median triangles drawn,
// y = median PSNR, labelled with the budget) and the truth's median
// frustum-culled triangle count `truth_triangles_median` named on the x
// axis. Infinite PSNR is not drawn (scatter_plot_svg skips it).
ScatterPlot far_budget_sweep_plot(const std::vector<FarBudgetSummary>& rows, double truth_triangles_median);

// The rows as an HTML <table> (budget, views, median triangles and their
// share of the truth's, median and worst PSNR).
std::string far_budget_sweep_table_html(const std::vector<FarBudgetSummary>& rows,
                                        double truth_triangles_median);

}  // namespace cellbake
