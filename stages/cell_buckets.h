// Items bucketed on a uniform grid of cells, stored as one array (compressed
// rows: the members of cell c follow those of cell c - 1), for spatial
// queries and pair tests over segments in the simplifier.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace cellbake {

class CellBuckets {
 public:
  // Buckets over `cell_count` cells. `for_each_cell(visit)` must call
  // visit(item, cell) for every cell of every item, items in increasing order
  // (item < 2^32, cell < cell_count), the same way each time: it is called
  // twice (count, then fill). Each bucket lists its items in increasing order.
  template <typename ForEachCell>
  CellBuckets(std::size_t cell_count, ForEachCell&& for_each_cell) : first_(cell_count + 1, 0) {
    for_each_cell([&](std::size_t, std::size_t cell) { ++first_[cell + 1]; });
    for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
    members_.resize(first_.back());
    std::vector<std::uint32_t> next(first_.begin(), first_.end() - 1);
    for_each_cell([&](std::size_t item, std::size_t cell) { members_[next[cell]++] = std::uint32_t(item); });
  }

  std::size_t cell_count() const { return first_.size() - 1; }
  // The items of cell c, in increasing order.
  std::span<const std::uint32_t> operator[](std::size_t c) const {
    return {members_.data() + first_[c], members_.data() + first_[c + 1]};
  }

 private:
  std::vector<std::uint32_t> first_;    // cell c holds members_[first_[c] .. first_[c + 1])
  std::vector<std::uint32_t> members_;
};

}  // namespace cellbake
