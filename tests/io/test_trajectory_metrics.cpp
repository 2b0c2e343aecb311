// Hand-computed cases for the TUM metrics (evaluation.md). The comparison with an independent
// numpy implementation of the TUM scripts on real fr1/xyz data is tests/tools/eval_reference.sh.
#include <gtest/gtest.h>

#include "jpcr/io/trajectory_metrics.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

// A smooth trajectory at `rate` Hz with rotation, like a hand-held camera.
Trajectory make_trajectory(int n, double rate = 30.0) {
  Trajectory t;
  for (int i = 0; i < n; ++i) {
    const double s = i / rate;
    Vector6d xi;
    xi << 0.3 * s, 0.1 * std::sin(s), 1.5 + 0.05 * s, 0.1 * s, -0.2 * std::sin(2 * s), 0.05;
    t.push_back({100.0 + s, se3_exp(xi)});
  }
  return t;
}

TEST(Metrics, IdenticalTrajectoriesGiveZero) {
  const Trajectory gt = make_trajectory(40);
  EXPECT_NEAR(compute_ate(gt, gt).translation.rmse, 0.0, 1e-12);
  const RpeResult rpe = compute_rpe(gt, gt, 1.0, DeltaUnit::kFrames);
  EXPECT_NEAR(rpe.translation.rmse, 0.0, 1e-12);
  EXPECT_NEAR(rpe.rotation.rmse, 0.0, 1e-6);
  const RelativeErrors rel = compute_relative_errors(gt, gt);
  EXPECT_NEAR(rel.translation_rms, 0.0, 1e-12);
  EXPECT_EQ(rel.pairs, 39u);
  EXPECT_NEAR(compute_drift(gt, gt).translation.back(), 0.0, 1e-12);
}

TEST(Metrics, GlobalRigidMotionOfTheEstimateIsInvisible) {
  const Trajectory gt = make_trajectory(40);
  const Eigen::Isometry3d G = se3_exp((Vector6d() << 1, -2, 3, 0.4, -0.5, 1.2).finished());
  Trajectory est = gt;
  for (auto& p : est)
    p.pose = G * p.pose;
  EXPECT_NEAR(compute_ate(gt, est).translation.rmse, 0.0, 1e-10);
  EXPECT_NEAR(compute_rpe(gt, est, 1.0, DeltaUnit::kFrames).translation.rmse, 0.0, 1e-10);
  EXPECT_NEAR(compute_relative_errors(gt, est).translation_rms, 0.0, 1e-10);
  EXPECT_NEAR(compute_drift(gt, est).translation.back(), 0.0, 1e-10);
}

TEST(Metrics, AteHandComputedCheckerboard) {
  // Four poses on a unit square; the estimate moves them ±d along z in a checkerboard pattern.
  // The pattern is uncorrelated with x and y and has zero mean, so the optimal alignment is the
  // identity and every point is off by exactly d: ATE = d.
  const double d = 0.01;
  const double xy[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  const double sign[4] = {+1, -1, -1, +1};
  Trajectory gt, est;
  for (int i = 0; i < 4; ++i) {
    StampedPose p;
    p.timestamp = i;
    p.pose.translation() = Eigen::Vector3d(xy[i][0], xy[i][1], 0.0);
    gt.push_back(p);
    p.pose.translation().z() = sign[i] * d;
    est.push_back(p);
  }
  const AteResult ate = compute_ate(gt, est);
  EXPECT_NEAR(ate.translation.rmse, d, 1e-12);
  EXPECT_NEAR(ate.translation.max, d, 1e-12);
  EXPECT_LT((ate.alignment.matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
}

TEST(Metrics, RpeAndRelativeErrorsHandComputedSinglePerturbation) {
  // Frame 4 of 10 is displaced by δ in the world. Exactly the two relative motions touching it
  // are wrong, each by |δ| (rotations preserve length). TUM RPE per frame skips pairs ending at
  // the last frame: pairs (i, i+1) for i = 0..7, so RMSE = δ·√(2/8). The paper-style errors use
  // all 9 consecutive pairs: RMS = δ·√(2/9).
  const Trajectory gt = make_trajectory(10);
  Trajectory est = gt;
  const Eigen::Vector3d delta(0.003, -0.004, 0.0);  // |δ| = 5 mm
  est[4].pose.pretranslate(delta);
  const RpeResult rpe = compute_rpe(gt, est, 1.0, DeltaUnit::kFrames);
  EXPECT_EQ(rpe.translation.count, 8u);
  EXPECT_NEAR(rpe.translation.rmse, 0.005 * std::sqrt(2.0 / 8.0), 1e-12);
  EXPECT_NEAR(rpe.translation.max, 0.005, 1e-12);
  EXPECT_NEAR(rpe.rotation.rmse, 0.0, 1e-6);
  const RelativeErrors rel = compute_relative_errors(gt, est);
  EXPECT_EQ(rel.pairs, 9u);
  EXPECT_NEAR(rel.translation_rms, 0.005 * std::sqrt(2.0 / 9.0), 1e-12);
}

TEST(Metrics, RpePerSecondPairsFramesOneSecondApart) {
  // 30 Hz for 3 s (90 frames): pairs (i, i+30). The estimate drifts in yaw about the world
  // origin at ω rad/s, e_k = Rz(ω s_k) g_k. The TUM error of a pair is then g_i⁻¹ Rz(ω) g_i, a
  // conjugate of Rz(ω), so its rotation angle is exactly ω (per second).
  const Trajectory gt = make_trajectory(90);
  Trajectory est = gt;
  const double omega = 0.01;  // rad/s
  for (auto& p : est) {
    const double s = p.timestamp - 100.0;
    p.pose = Eigen::AngleAxisd(omega * s, Eigen::Vector3d::UnitZ()) * p.pose;
  }
  const RpeResult rpe = compute_rpe(gt, est, 1.0, DeltaUnit::kSeconds);
  // i = 0..59 pair with j = i + 30; j = 89 (the last) is skipped, so 59 pairs.
  EXPECT_EQ(rpe.rotation.count, 59u);
  EXPECT_NEAR(rpe.rotation.rmse, omega * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(rpe.rotation.max, omega * 180.0 / M_PI, 1e-9);
}

TEST(Metrics, DriftGrowsLinearlyWithConstantStepError) {
  // Rail: 1 cm per frame along x; the estimate overshoots every step by 0.1 mm.
  Trajectory gt, est;
  for (int i = 0; i <= 100; ++i) {
    StampedPose p;
    p.timestamp = i * 0.1;
    p.pose.translation() = Eigen::Vector3d(0.01 * i, 0, 0);
    gt.push_back(p);
    p.pose.translation() = Eigen::Vector3d(0.0101 * i, 0, 0) + Eigen::Vector3d(5, 5, 5);
    est.push_back(p);
  }
  const DriftCurve drift = compute_drift(gt, est);
  EXPECT_NEAR(drift.distance.back(), 1.0, 1e-12);
  EXPECT_NEAR(drift.translation.back(), 0.01, 1e-12);
  EXPECT_NEAR(drift.translation_per_metre, 0.01, 1e-12);
  EXPECT_NEAR(drift.translation[50], 0.005, 1e-12);
}

TEST(Metrics, TooFewAssociationsIsAnError) {
  const Trajectory gt = make_trajectory(5);
  Trajectory est = gt;
  for (auto& p : est)
    p.timestamp += 10.0;
  EXPECT_THROW(compute_ate(gt, est), InputError);
}

TEST(Metrics, ErrorStatistics) {
  const ErrorStatistics s = error_statistics({3.0, 4.0, 1.0, 2.0});
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4.0));
}

}  // namespace
}  // namespace jpcr
