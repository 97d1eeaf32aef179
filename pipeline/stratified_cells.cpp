#include "pipeline/stratified_cells.h"

#include <algorithm>
#include <map>

namespace cellbake {
namespace {

// Bits of x spread to every third position.
std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

std::uint64_t morton(const CellSpec& c) {
  return spread3(std::uint64_t(std::max(c.gx, 0))) | spread3(std::uint64_t(std::max(c.gy, 0))) << 1 |
         spread3(std::uint64_t(std::max(c.gz, 0))) << 2;
}

}  // namespace

std::vector<std::size_t> stratum_shares(const std::vector<std::size_t>& sizes, std::size_t k) {
  const std::size_t n = sizes.size();
  std::vector<std::size_t> share(n, 0);
  std::size_t total = 0, nonempty = 0;
  for (std::size_t s : sizes) total += s, nonempty += s > 0;
  k = std::min(k, total);
  if (k == 0) return share;
  if (k < nonempty) {  // fewer picks than strata: one each to strata spread evenly over the order
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < n; ++i)
      if (sizes[i] > 0) order.push_back(i);
    for (std::size_t j = 0; j < k; ++j) share[order[(2 * j + 1) * order.size() / (2 * k)]] = 1;
    return share;
  }
  std::size_t given = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (sizes[i] > 0) share[i] = 1, ++given;
  while (given < k) {  // the stratum furthest below its proportional share gets the next pick
    std::size_t best = n;
    double best_gap = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (share[i] >= sizes[i]) continue;
      const double gap = double(sizes[i]) * double(k) / double(total) - double(share[i]);
      if (best == n || gap > best_gap) best = i, best_gap = gap;
    }
    ++share[best];
    ++given;
  }
  return share;
}

std::vector<CellSpec> stratified_cells(const std::vector<CellSpec>& cells, std::size_t k) {
  if (k >= cells.size()) return cells;
  std::map<int, std::vector<CellSpec>> by_region;
  for (const CellSpec& c : cells) by_region[c.region].push_back(c);
  std::vector<std::size_t> sizes;
  for (const auto& [region, list] : by_region) sizes.push_back(list.size());
  const std::vector<std::size_t> shares = stratum_shares(sizes, k);
  std::vector<CellSpec> picked;
  std::size_t r = 0;
  for (auto& [region, list] : by_region) {
    const std::size_t a = shares[r++], m = list.size();
    if (a == 0) continue;
    std::stable_sort(list.begin(), list.end(),
                     [](const CellSpec& x, const CellSpec& y) { return morton(x) < morton(y); });
    for (std::size_t i = 0; i < a; ++i) picked.push_back(list[(2 * i + 1) * m / (2 * a)]);
  }
  std::sort(picked.begin(), picked.end(), [](const CellSpec& x, const CellSpec& y) { return x.id < y.id; });
  return picked;
}

}  // namespace cellbake
