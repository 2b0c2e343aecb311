// Is one estimate of a trajectory better than another, or is the difference within what the
// frames can tell? Two estimates of the same sequence (say the pipeline and ICP-ftf) are
// compared on the per-frame relative errors (compute_relative_errors, paper Tables I-III) of the
// frame pairs both have: the ratio of their RMS errors, estimate / baseline, with a 95 %
// interval from a paired moving-block bootstrap (Künsch 1989). Pairs are resampled in blocks of
// consecutive pairs (length ⌈n^(1/3)⌉) because neighbouring pairs share a frame and so their
// errors are correlated; both estimates are resampled on the same pairs, so errors the two share
// (ground-truth noise, a hard stretch of the sequence) cancel in the ratio.
//
//   const RelativeErrors a = compute_relative_errors(gt, pipeline), b = compute_relative_errors(gt,
//   icp); const PairedComparison c = compare_relative_errors(a, b); if (c.translation.high < 1.0)
//   ...  // the pipeline is better, beyond the bootstrap's doubt
#pragma once

#include <cstdint>
#include <string>

#include "jpcr/io/trajectory_metrics.hpp"

namespace jpcr {

struct RatioInterval {
  double ratio = 1.0;  // RMS(estimate) / RMS(baseline) over the common pairs
  double low = 1.0;    // 2.5 % and 97.5 % quantiles of the bootstrap ratios
  double high = 1.0;

  /// "better" (high < 1), "worse" (low > 1) or "indistinguishable".
  const char* verdict() const;
};

struct PairedComparison {
  std::size_t pairs = 0;  // frame pairs both estimates have
  std::size_t block = 0;  // bootstrap block length, pairs
  RatioInterval translation, rotation;
};

/// Throws InputError when fewer than 10 pairs are common (or the baseline's errors are all 0).
/// Deterministic for a given seed.
PairedComparison compare_relative_errors(const RelativeErrors& estimate,
                                         const RelativeErrors& baseline, int resamples = 2000,
                                         std::uint64_t seed = 1);

}  // namespace jpcr
