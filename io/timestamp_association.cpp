#include "jpcr/io/timestamp_association.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace jpcr {

std::vector<std::pair<std::size_t, std::size_t>> associate_timestamps(const std::vector<double>& a,
                                                                      const std::vector<double>& b,
                                                                      double max_difference) {
  // Candidates within the window; b is sorted through an index so the window search is a
  // binary search instead of the O(|a||b|) loop of associate.py (same result).
  // A stamp that is not finite matches nothing (a NaN in the sort broke its ordering).
  std::vector<std::size_t> order_b;
  for (std::size_t j = 0; j < b.size(); ++j)
    if (std::isfinite(b[j])) order_b.push_back(j);
  std::sort(order_b.begin(), order_b.end(),
            [&](std::size_t x, std::size_t y) { return b[x] < b[y]; });
  std::vector<double> sorted_b(order_b.size());
  for (std::size_t k = 0; k < order_b.size(); ++k)
    sorted_b[k] = b[order_b[k]];

  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i])) continue;
    auto lo = std::lower_bound(sorted_b.begin(), sorted_b.end(), a[i] - max_difference);
    for (auto it = lo; it != sorted_b.end() && *it <= a[i] + max_difference; ++it) {
      const double diff = std::abs(a[i] - *it);
      if (diff < max_difference) {
        candidates.emplace_back(diff, i, order_b[static_cast<std::size_t>(it - sorted_b.begin())]);
      }
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<std::size_t, std::size_t>> matches;
  for (const auto& [diff, i, j] : candidates) {
    if (used_a[i] || used_b[j]) continue;
    used_a[i] = used_b[j] = true;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

std::size_t closest_index(const std::vector<double>& stamps, double t) {
  if (stamps.empty()) return 0;
  const auto it = std::lower_bound(stamps.begin(), stamps.end(), t);
  if (it == stamps.begin()) return 0;
  if (it == stamps.end()) return stamps.size() - 1;
  const std::size_t j = static_cast<std::size_t>(it - stamps.begin());
  return (t - stamps[j - 1] <= stamps[j] - t) ? j - 1 : j;
}

}  // namespace jpcr
