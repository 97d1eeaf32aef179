#include "stages/model_analysis/storey_units.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace cellbake {
namespace {

const ModelUnit kUnits[] = {{"centimetres", 0.01}, {"inches", 0.0254}, {"millimetres", 0.001}, {"feet", 0.3048}};

std::string text(const char* format, double a, double b = 0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

}  // namespace

StoreyUnits units_from_storeys(const std::vector<double>& heights, const std::vector<std::uint64_t>& rays,
                               const StoreyUnitsParams& params) {
  if (heights.size() != rays.size()) throw std::invalid_argument("units_from_storeys: heights and rays differ in length");
  StoreyUnits out;
  const std::uint64_t most = rays.empty() ? 0 : *std::max_element(rays.begin(), rays.end());
  std::vector<double> main;
  for (std::size_t i = 0; i < heights.size(); ++i)
    if (double(rays[i]) >= params.main_share * double(most) && rays[i] > 0) main.push_back(heights[i]);
  if (main.size() < 2) return out;
  std::vector<double> gaps;
  for (std::size_t i = 1; i < main.size(); ++i) gaps.push_back(main[i] - main[i - 1]);
  std::sort(gaps.begin(), gaps.end());
  const std::size_t n = gaps.size();
  out.storey = n % 2 ? gaps[n / 2] : 0.5 * (gaps[n / 2 - 1] + gaps[n / 2]);
  const auto plausible = [&](double metres) {
    return metres >= params.min_storey_m && metres <= params.max_storey_m;
  };
  out.metres_plausible = plausible(out.storey);
  const std::string between =
      text("the main floors are %.4g units apart", out.storey) + (main.size() > 2 ? " (median)" : "");
  if (out.metres_plausible) {
    out.evidence = between + ", a storey in metres";
    return out;
  }
  for (const ModelUnit& u : kUnits)
    if (plausible(out.storey * u.metres)) out.fitting.push_back(u);
  const auto off = [&](const ModelUnit& u) { return std::abs(std::log(out.storey * u.metres / params.typical_storey_m)); };
  std::stable_sort(out.fitting.begin(), out.fitting.end(),
                   [&](const ModelUnit& a, const ModelUnit& b) { return off(a) < off(b); });
  out.evidence = between + text(": no storey in metres (%.2f-%.2f m is)", params.min_storey_m, params.max_storey_m);
  for (std::size_t i = 0; i < out.fitting.size(); ++i)
    out.evidence += std::string(i == 0 ? "; one in " : " or ") + out.fitting[i].name +
                    text(" (%.2f m)", out.storey * out.fitting[i].metres);
  if (out.fitting.empty()) out.evidence += ", nor in centimetres, inches, millimetres or feet";
  return out;
}

}  // namespace cellbake
