// Curvature error against ground truth (evaluation.md "Curvature"): RMS of κ₁ and κ₂ (1/m) over
// pixels valid in both the estimate and the ground truth, and coverage, the fraction of
// ground-truth-valid pixels the method returns.
#pragma once

#include <cstddef>

#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct CurvatureErrors {
  double rms_k1 = 0.0;       // 1/m
  double rms_k2 = 0.0;       // 1/m
  double rms = 0.0;          // 1/m, over both κ₁ and κ₂
  double median_abs = 0.0;   // 1/m, median of |Δκ₁| and |Δκ₂| together
  double coverage = 0.0;     // compared / ground-truth-valid pixels
  std::size_t compared = 0;  // pixels valid in both
  std::size_t gt_valid = 0;  // pixels with ground truth
  std::size_t frames = 0;
};

/// Accumulates frames; throws InputError when a frame's sizes differ.
class CurvatureErrorAccumulator {
 public:
  void add(const CurvatureImage& ground_truth, const CurvatureImage& estimate);
  CurvatureErrors result() const;

 private:
  double sum_k1_ = 0.0, sum_k2_ = 0.0;
  std::size_t compared_ = 0, gt_valid_ = 0, frames_ = 0;
  std::vector<float> abs_errors_;  // for the median
};

}  // namespace jpcr
