#include "runner/verify/far_budget_sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

namespace cellbake {
namespace {

// Median of `v` (sorted here; the mean of the middle two for an even count, infinities kept).
double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  if (n % 2) return v[n / 2];
  const double a = v[n / 2 - 1], b = v[n / 2];
  return a == b ? a : 0.5 * (a + b);
}

std::string number(double v, const char* format) {
  if (std::isnan(v)) return "&ndash;";
  if (std::isinf(v)) return v > 0 ? "&infin;" : "-&infin;";
  char text[64];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

}  // namespace

std::vector<std::uint64_t> parse_far_budget_sweep(const std::string& text) {
  std::vector<std::uint64_t> budgets;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    std::size_t used = 0;
    unsigned long long value = 0;
    try {
      if (item.empty() || item[0] == '-' || item[0] == '+') throw std::invalid_argument(item);
      value = std::stoull(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || used == 0 || value == 0)
      throw std::invalid_argument("--far-budget-sweep: \"" + item + "\" is not a positive triangle count");
    budgets.push_back(value);
    start = end + 1;
  }
  std::sort(budgets.begin(), budgets.end());
  budgets.erase(std::unique(budgets.begin(), budgets.end()), budgets.end());
  return budgets;
}

std::vector<FarBudgetSummary> summarise_far_budget_sweep(
    const std::vector<std::vector<FarBudgetPoint>>& views) {
  std::map<std::uint64_t, std::pair<std::vector<double>, std::vector<double>>> by_budget;  // triangles, psnr
  for (const auto& points : views)
    for (const FarBudgetPoint& p : points) {
      auto& [triangles, psnr] = by_budget[p.far_budget];
      triangles.push_back(double(p.triangles));
      psnr.push_back(p.psnr_db);
    }
  std::vector<FarBudgetSummary> rows;
  for (const auto& [budget, values] : by_budget) {
    FarBudgetSummary row;
    row.far_budget = budget;
    row.views = values.first.size();
    row.triangles_median = median(values.first);
    row.psnr_median_db = median(values.second);
    row.psnr_worst_db = *std::min_element(values.second.begin(), values.second.end());
    rows.push_back(row);
  }
  return rows;
}

ScatterPlot far_budget_sweep_plot(const std::vector<FarBudgetSummary>& rows, double truth_triangles_median) {
  ScatterPlot plot;
  plot.title = "Speed against error: median PSNR vs triangles drawn, far budget swept";
  plot.x_label = "median triangles drawn per view (the truth draws " + format_tick(truth_triangles_median) +
                 ", frustum-culled)";
  plot.y_label = "median PSNR over random views, dB";
  PlotSeries curve{"far budget", "#1f77b4", {}};
  for (const FarBudgetSummary& row : rows)
    curve.points.push_back({row.triangles_median, row.psnr_median_db,
                            "far budget " + std::to_string(row.far_budget) + ": " +
                                number(row.psnr_median_db, "%.2f") + " dB at " +
                                number(row.triangles_median, "%.0f") + " triangles"});
  plot.series.push_back(std::move(curve));
  return plot;
}

std::string far_budget_sweep_table_html(const std::vector<FarBudgetSummary>& rows,
                                        double truth_triangles_median) {
  std::string h =
      "<table><tr><th>far budget</th><th>views</th><th>median triangles drawn</th><th>of the truth's</th>"
      "<th>median PSNR, dB</th><th>worst PSNR, dB</th></tr>\n";
  for (const FarBudgetSummary& row : rows)
    h += "<tr><td>" + std::to_string(row.far_budget) + "</td><td>" + std::to_string(row.views) + "</td><td>" +
         number(row.triangles_median, "%.0f") + "</td><td>" +
         number(truth_triangles_median > 0 ? row.triangles_median / truth_triangles_median : NAN, "%.2f") +
         "</td><td>" + number(row.psnr_median_db, "%.2f") + "</td><td>" + number(row.psnr_worst_db, "%.2f") +
         "</td></tr>\n";
  return h + "</table>\n";
}

}  // namespace cellbake
