#include "jpcr/io/trajectory_metrics.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/SVD>

#include "jpcr/io/timestamp_association.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::vector<double> stamps_of(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const StampedPose& p : trajectory)
    stamps.push_back(p.timestamp);
  return stamps;
}

Trajectory sorted_by_time(Trajectory trajectory) {
  std::stable_sort(
      trajectory.begin(), trajectory.end(),
      [](const StampedPose& a, const StampedPose& b) { return a.timestamp < b.timestamp; });
  return trajectory;
}

// TUM's ominus(a, b) = a⁻¹ b: the motion from a to b.
Eigen::Isometry3d ominus(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return a.inverse() * b;
}

}  // namespace

ErrorStatistics error_statistics(const std::vector<double>& errors) {
  ErrorStatistics s;
  s.count = errors.size();
  if (errors.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
    s.max = std::max(s.max, e);
  }
  const double n = static_cast<double>(errors.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t mid = sorted.size() / 2;
  s.median = sorted.size() % 2 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  return s;
}

AteResult compute_ate(const Trajectory& ground_truth, const Trajectory& estimate,
                      double max_difference) {
  const auto matches =
      associate_timestamps(stamps_of(ground_truth), stamps_of(estimate), max_difference);
  if (matches.size() < 3) {
    throw InputError("ATE: only " + std::to_string(matches.size()) +
                     " poses associate between ground truth and estimate (need 3); check the "
                     "timestamps and --max-difference");
  }
  const Eigen::Index n = static_cast<Eigen::Index>(matches.size());
  Eigen::Matrix3Xd model(3, n), data(3, n);  // model = estimate, data = ground truth
  for (Eigen::Index k = 0; k < n; ++k) {
    data.col(k) = ground_truth[matches[k].first].pose.translation();
    model.col(k) = estimate[matches[k].second].pose.translation();
  }
  // Horn/Kabsch without scale, as evaluate_ate.py's align(): W = Σ m̃ d̃ᵀ, svd(Wᵀ) = U S Vᵀ.
  const Eigen::Vector3d model_mean = model.rowwise().mean(), data_mean = data.rowwise().mean();
  const Eigen::Matrix3d W =
      (model.colwise() - model_mean) * (data.colwise() - data_mean).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(W.transpose(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;
  const Eigen::Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();

  AteResult result;
  result.alignment.linear() = R;
  result.alignment.translation() = data_mean - R * model_mean;
  std::vector<double> errors(matches.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    errors[static_cast<std::size_t>(k)] =
        (result.alignment * Eigen::Vector3d(model.col(k)) - data.col(k)).norm();
  }
  result.translation = error_statistics(errors);
  return result;
}

RpeResult compute_rpe(const Trajectory& ground_truth_in, const Trajectory& estimate_in,
                      double delta, DeltaUnit unit) {
  const Trajectory gt = sorted_by_time(ground_truth_in), est = sorted_by_time(estimate_in);
  if (gt.size() < 2 || est.size() < 2) {
    throw InputError("RPE: need at least 2 poses in both ground truth and estimate");
  }
  const std::vector<double> stamps_gt = stamps_of(gt), stamps_est = stamps_of(est);
  std::vector<double> index_est(est.size());
  for (std::size_t i = 0; i < est.size(); ++i) {
    index_est[i] = unit == DeltaUnit::kSeconds ? stamps_est[i] : static_cast<double>(i);
  }
  std::vector<double> intervals;
  for (std::size_t i = 1; i < stamps_gt.size(); ++i) {
    intervals.push_back(stamps_gt[i] - stamps_gt[i - 1]);
  }
  const double max_gt_difference = 2.0 * error_statistics(intervals).median;

  std::vector<double> translation, rotation;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const std::size_t j = closest_index(index_est, index_est[i] + delta);
    if (j == est.size() - 1) continue;  // as evaluate_rpe.py
    const std::size_t g0 = closest_index(stamps_gt, stamps_est[i]);
    const std::size_t g1 = closest_index(stamps_gt, stamps_est[j]);
    if (std::abs(stamps_gt[g0] - stamps_est[i]) > max_gt_difference ||
        std::abs(stamps_gt[g1] - stamps_est[j]) > max_gt_difference) {
      continue;
    }
    const Eigen::Isometry3d error =
        ominus(ominus(est[j].pose, est[i].pose), ominus(gt[g1].pose, gt[g0].pose));
    translation.push_back(error.translation().norm());
    rotation.push_back(rotation_angle(error.linear()) * kRadToDeg);
  }
  if (translation.empty()) {
    throw InputError(
        "RPE: no pose pair could be formed (sequence shorter than delta, or the "
        "timestamps do not overlap the ground truth)");
  }
  return {error_statistics(translation), error_statistics(rotation)};
}

RelativeErrors compute_relative_errors(const Trajectory& ground_truth_in,
                                       const Trajectory& estimate_in, double max_difference) {
  // In time order, as the adjacency of estimate poses below assumes (compute_rpe does the same).
  const Trajectory ground_truth = sorted_by_time(ground_truth_in);
  const Trajectory estimate = sorted_by_time(estimate_in);
  const auto matches =
      associate_timestamps(stamps_of(ground_truth), stamps_of(estimate), max_difference);
  RelativeErrors result;
  double sum_t = 0.0, sum_r = 0.0;
  for (std::size_t k = 1; k < matches.size(); ++k) {
    // Consecutive estimates only: across a pose without ground truth (a gap in the motion
    // capture) the pair would be a longer motion, counted as one frame's.
    if (matches[k].second != matches[k - 1].second + 1) continue;
    const Eigen::Isometry3d gt_motion =
        ominus(ground_truth[matches[k - 1].first].pose, ground_truth[matches[k].first].pose);
    const Eigen::Isometry3d est_motion =
        ominus(estimate[matches[k - 1].second].pose, estimate[matches[k].second].pose);
    const Eigen::Isometry3d error = ominus(gt_motion, est_motion);
    const double t = error.translation().norm(), r = rotation_angle(error.linear());
    result.translation.push_back(t);
    result.rotation.push_back(r);
    result.ground_truth_frames.emplace_back(matches[k - 1].first, matches[k].first);
    sum_t += t * t;
    sum_r += r * r;
  }
  result.pairs = result.translation.size();
  if (result.pairs > 0) {
    result.translation_rms = std::sqrt(sum_t / static_cast<double>(result.pairs));
    result.rotation_rms = std::sqrt(sum_r / static_cast<double>(result.pairs));
  }
  return result;
}

DriftCurve compute_drift(const Trajectory& ground_truth_in, const Trajectory& estimate_in,
                         double max_difference) {
  // The distance travelled is summed in time order, whatever order a library caller gives.
  const Trajectory ground_truth = sorted_by_time(ground_truth_in);
  const Trajectory estimate = sorted_by_time(estimate_in);
  const auto matches =
      associate_timestamps(stamps_of(ground_truth), stamps_of(estimate), max_difference);
  DriftCurve drift;
  if (matches.empty()) return drift;
  const Eigen::Isometry3d anchor =
      ground_truth[matches[0].first].pose * estimate[matches[0].second].pose.inverse();
  double travelled = 0.0;
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const Eigen::Isometry3d& gt = ground_truth[matches[k].first].pose;
    if (k > 0) {
      travelled +=
          (gt.translation() - ground_truth[matches[k - 1].first].pose.translation()).norm();
    }
    const Eigen::Isometry3d est = anchor * estimate[matches[k].second].pose;
    drift.distance.push_back(travelled);
    drift.translation.push_back((est.translation() - gt.translation()).norm());
    drift.rotation.push_back(rotation_angle(gt.linear().transpose() * est.linear()) * kRadToDeg);
  }
  if (travelled > 0.0) {
    drift.translation_per_metre = drift.translation.back() / travelled;
    drift.rotation_per_metre = drift.rotation.back() / travelled;
  }
  return drift;
}

}  // namespace jpcr
