// Timestamp association as in the TUM RGB-D tools (associate.py): every pair closer than
// max_difference is a candidate, and pairs are taken greedily by increasing time difference,
// each timestamp at most once.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace jpcr {

/// Returns index pairs (i into a, j into b), sorted by i. a and b need not be sorted; a stamp
/// that is not finite matches nothing.
std::vector<std::pair<std::size_t, std::size_t>> associate_timestamps(const std::vector<double>& a,
                                                                      const std::vector<double>& b,
                                                                      double max_difference);

/// Index of the element of the sorted vector `stamps` closest to t (TUM find_closest_index).
std::size_t closest_index(const std::vector<double>& stamps, double t);

}  // namespace jpcr
