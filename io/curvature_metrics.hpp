// Curvature error against ground truth (evaluation.md "Curvature"): RMS of κ₁ and κ₂ (1/m) over
// pixels valid in both the estimate and the ground truth, and coverage, the fraction of
// ground-truth-valid pixels the method returns.
//
// With a support radius R > 0 only interior pixels count: those whose whole (2R+1)² window has
// ground truth. The ground truth is NaN on creases and silhouettes (synthetic_ray_caster.hpp), so
// these are the pixels where a patch fit of radius R sees one smooth surface. Near an edge every
// patch method fits a surface that is not there, and those pixels can swamp the RMS.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct CurvatureErrors {
  double rms_k1 = 0.0;       // 1/m
  double rms_k2 = 0.0;       // 1/m
  double rms = 0.0;          // 1/m, over both κ₁ and κ₂
  double median_abs = 0.0;   // 1/m, median of |Δκ₁| and |Δκ₂| together, to 1e-4 relative
                             // between 1e-9 (0 below) and 1e9 (1e9 above)
  double coverage = 0.0;     // compared / ground-truth-valid pixels
  std::size_t compared = 0;  // pixels valid in both
  std::size_t gt_valid = 0;  // pixels with ground truth
  std::size_t frames = 0;
  int support_radius = 0;  // px; > 0: only interior pixels counted (header)
  // With the estimate's sd maps (curvature_spread.hpp), over the compared pixels that have a
  // finite sd, with e = √((Δκ₁² + Δκ₂²) / 2) per pixel:
  std::size_t sd_compared = 0;  // such pixels (0: no sd given)
  double sd_rms = 0.0;          // RMS of the sd, 1/m
  double rms_where_sd = 0.0;    // RMS of e over the same pixels, 1/m (near sd_rms: calibrated)
  double within_2sd = 0.0;      // fraction with e < 2 sd (about 0.98 for Gaussian errors at sd)
};

/// Accumulates frames; throws InputError when a frame's sizes differ.
class CurvatureErrorAccumulator {
 public:
  static constexpr int kMaxSupportRadius = 16384;
  /// `support_radius` R in pixels, 0..kMaxSupportRadius (0: every ground-truth pixel counts);
  /// throws InputError outside that range.
  explicit CurvatureErrorAccumulator(int support_radius = 0);

  /// `sd`, when given, is the estimate's sd map of the same size (throws InputError otherwise).
  void add(const CurvatureImage& ground_truth, const CurvatureImage& estimate,
           const Image<float>* sd = nullptr);
  CurvatureErrors result() const;

 private:
  int support_radius_ = 0;
  double sum_k1_ = 0.0, sum_k2_ = 0.0;
  std::size_t compared_ = 0, gt_valid_ = 0, frames_ = 0;
  double sum_sd2_ = 0.0, sum_e2_where_sd_ = 0.0;
  std::size_t sd_compared_ = 0, within_2sd_ = 0;
  // |Δκ| on a logarithmic scale for the median: constant memory however many frames (a list of
  // every error took 8 bytes a pixel, 2.4 GB for 1000 frames at 640x480). Bin 0 holds errors
  // below kMedianFloor, bin k ≥ 1 [floor·r^(k−1), floor·r^k) with r = 1 + kMedianStep, the last
  // also everything above.
  static constexpr double kMedianFloor = 1e-9, kMedianStep = 1e-4, kMedianCeiling = 1e9;
  std::vector<std::uint64_t> abs_error_bins_;
  void add_abs_error(double e);
};

}  // namespace jpcr
