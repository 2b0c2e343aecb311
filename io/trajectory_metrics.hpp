// Trajectory error metrics with the TUM RGB-D benchmark conventions (evaluation.md), so numbers
// compare with the literature:
//  - ATE: associate within max_difference, rigid Horn/Kabsch alignment without scale, RMSE (m).
//  - RPE: no alignment; pairs (i, j) with j the estimate closest to i + delta (frames or seconds),
//    as evaluate_rpe.py --fixed_delta (pairs ending at the last estimate are skipped, as there).
//  - Paper-style relative errors: RMS translation (m) and rotation (rad) of the relative pose of
//    every pair of consecutive associated frames (paper Tables I–III).
//  - Drift: accumulated error against distance travelled after anchoring the first pose.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "jpcr/quadric/frame.hpp"

namespace jpcr {

struct ErrorStatistics {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
  std::size_t count = 0;
};

ErrorStatistics error_statistics(const std::vector<double>& errors);

struct AteResult {
  ErrorStatistics translation;                                  // m
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();  // maps estimate onto ground truth
};

/// Throws InputError when fewer than 3 pairs associate.
AteResult compute_ate(const Trajectory& ground_truth, const Trajectory& estimate,
                      double max_difference = 0.02);

enum class DeltaUnit { kFrames, kSeconds };

struct RpeResult {
  ErrorStatistics translation;  // m per delta
  ErrorStatistics rotation;     // deg per delta
};

/// Throws InputError when no pair can be formed.
RpeResult compute_rpe(const Trajectory& ground_truth, const Trajectory& estimate, double delta,
                      DeltaUnit unit);

struct RelativeErrors {
  double translation_rms = 0.0;  // m
  double rotation_rms = 0.0;     // rad
  std::size_t pairs = 0;
  std::vector<double> translation;  // per consecutive pair, m
  std::vector<double> rotation;     // per consecutive pair, rad
  /// Per pair, the ground-truth indices of its two frames: the key that pairs up two estimates
  /// of the same sequence (trajectory_comparison.hpp).
  std::vector<std::pair<std::size_t, std::size_t>> ground_truth_frames;
};

/// The paper's relative error: per pair of consecutive estimate poses that both have ground
/// truth within max_difference (s), the error of the estimated motion, in time order. A pair
/// that spans an estimate pose without ground truth is left out. ground_truth_frames index the
/// ground truth sorted by time (as a file gives it).
RelativeErrors compute_relative_errors(const Trajectory& ground_truth, const Trajectory& estimate,
                                       double max_difference = 0.02);

struct DriftCurve {
  std::vector<double> distance;        // m travelled along the ground truth
  std::vector<double> translation;     // m, |t_est − t_gt| after anchoring the first pose
  std::vector<double> rotation;        // deg
  double translation_per_metre = 0.0;  // final translation error / distance travelled
  double rotation_per_metre = 0.0;     // deg / m
};

DriftCurve compute_drift(const Trajectory& ground_truth, const Trajectory& estimate,
                         double max_difference = 0.02);

}  // namespace jpcr
