// Hand-computed cases for the TUM metrics (evaluation.md). The comparison with an independent
// numpy implementation of the TUM scripts on real fr1/xyz data is tests/tools/eval_reference.sh.
#include <random>

#include <gtest/gtest.h>

#include "jpcr/io/trajectory_comparison.hpp"
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

// Ground truth missing for frames 4 and 5: the pairs (3, 4), (4, 5) and (5, 6) are left out,
// and (3, 6), a motion of three frames, is not counted as one frame's.
TEST(Metrics, RelativeErrorsSkipPairsAcrossAGroundTruthGap) {
  const Trajectory full = make_trajectory(10);
  Trajectory gt;
  for (std::size_t i = 0; i < full.size(); ++i)
    if (i != 4 && i != 5) gt.push_back(full[i]);
  Trajectory est = full;
  est[6].pose.pretranslate(Eigen::Vector3d(0.0, 0.0, 0.01));  // moves pairs (5, 6) and (6, 7)
  const RelativeErrors rel = compute_relative_errors(gt, est);
  EXPECT_EQ(rel.pairs, 6u);
  // Of pairs (6, 7) [error 1 cm] and (3, 6) [left out], only (6, 7) counts: 1 cm in 6 pairs
  // (counting (3, 6) gives 1 cm in two of 7).
  EXPECT_NEAR(rel.translation_rms, 0.01 / std::sqrt(6.0), 1e-12);
  // An estimate out of time order gives the same pairs.
  const RelativeErrors reversed = compute_relative_errors(gt, Trajectory(est.rbegin(), est.rend()));
  EXPECT_EQ(reversed.pairs, 6u);
  EXPECT_EQ(reversed.translation_rms, rel.translation_rms);
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

// The distance is summed in time order: a library caller's unsorted ground truth (two poses
// swapped) gave 2.5 m for a 0.9 m path.
TEST(Metrics, DriftSumsTheDistanceInTimeOrder) {
  Trajectory gt, est;
  for (int i = 0; i < 10; ++i) {
    StampedPose p;
    p.timestamp = i * 0.1;
    p.pose.translation() = Eigen::Vector3d(0.1 * i, 0, 0);
    gt.push_back(p);
    p.pose.translation() = Eigen::Vector3d(0.101 * i, 0, 0);
    est.push_back(p);
  }
  std::swap(gt[2], gt[7]);
  const DriftCurve drift = compute_drift(gt, est);
  EXPECT_NEAR(drift.distance.back(), 0.9, 1e-12);
  EXPECT_NEAR(drift.translation_per_metre, 0.01, 1e-12);
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

// An estimate of `gt` whose every frame-to-frame motion is off by an independent Gaussian
// twist (sigma_t m, sigma_r rad per axis): its per-pair relative errors are exactly those twists.
Trajectory with_step_noise(const Trajectory& gt, double sigma_t, double sigma_r,
                           std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Trajectory est{gt[0]};
  for (std::size_t i = 1; i < gt.size(); ++i) {
    Vector6d noise;
    for (int k = 0; k < 6; ++k)
      noise(k) = (k < 3 ? sigma_t : sigma_r) * g(rng);
    const Eigen::Isometry3d motion = gt[i - 1].pose.inverse() * gt[i].pose;
    est.push_back({gt[i].timestamp, est.back().pose * motion * se3_exp(noise)});
  }
  return est;
}

TEST(Comparison, AnEstimateAgainstItselfIsExactlyEven) {
  const Trajectory gt = make_trajectory(100);
  const RelativeErrors a = compute_relative_errors(gt, with_step_noise(gt, 1e-3, 1e-3, 1));
  const PairedComparison c = compare_relative_errors(a, a);
  EXPECT_EQ(c.pairs, 99u);
  EXPECT_EQ(c.block, 5u);  // ⌈99^(1/3)⌉
  EXPECT_DOUBLE_EQ(c.translation.ratio, 1.0);
  EXPECT_DOUBLE_EQ(c.translation.low, 1.0);
  EXPECT_DOUBLE_EQ(c.rotation.high, 1.0);
  EXPECT_STREQ(c.translation.verdict(), "indistinguishable");
}

// Half the noise: the ratio of RMS errors is 0.5 up to sampling. Each sum of squares over 299
// pairs is σ² χ²(897), relative sd √(2/897) = 4.7 %, so the ratio's sd is about 1.7 %; the
// bounds below are more than 3.5 of them.
TEST(Comparison, HalfTheNoiseIsBetterAndTheIntervalSaysSo) {
  const Trajectory gt = make_trajectory(300);
  const RelativeErrors est = compute_relative_errors(gt, with_step_noise(gt, 1e-3, 2e-3, 2));
  const RelativeErrors base = compute_relative_errors(gt, with_step_noise(gt, 2e-3, 4e-3, 3));
  const PairedComparison c = compare_relative_errors(est, base);
  for (const RatioInterval& r : {c.translation, c.rotation}) {
    EXPECT_NEAR(r.ratio, 0.5, 0.06);
    EXPECT_LT(r.low, r.ratio);
    EXPECT_GT(r.high, r.ratio);
    EXPECT_GT(r.high - r.low, 0.02);  // about 4 sd wide
    EXPECT_LT(r.high - r.low, 0.15);
    EXPECT_STREQ(r.verdict(), "better");
  }
  EXPECT_STREQ(compare_relative_errors(base, est).translation.verdict(), "worse");
}

// Equal noise: the 95 % interval holds 1 in about 95 % of independent trials (measured 189 of
// 200; binomial sd 1.5 %, so the bounds are 4.5 sd below and 2.7 sd above).
TEST(Comparison, EqualNoiseIntervalsCoverOneAtTheirLevel) {
  const Trajectory gt = make_trajectory(200);
  int covered = 0;
  const int trials = 200;
  for (int t = 0; t < trials; ++t) {
    const RelativeErrors a =
        compute_relative_errors(gt, with_step_noise(gt, 1e-3, 1e-3, 10 + 2 * t));
    const RelativeErrors b =
        compute_relative_errors(gt, with_step_noise(gt, 1e-3, 1e-3, 11 + 2 * t));
    const PairedComparison c = compare_relative_errors(a, b, 500, t);
    covered += c.translation.low <= 1.0 && 1.0 <= c.translation.high;
  }
  EXPECT_GE(covered, 0.88 * trials);
  EXPECT_LE(covered, 0.99 * trials) << "the intervals are too wide";
}

TEST(Comparison, TooFewCommonPairsIsAnError) {
  const Trajectory gt = make_trajectory(100);
  const RelativeErrors a = compute_relative_errors(gt, Trajectory(gt.begin(), gt.begin() + 8));
  const RelativeErrors b = compute_relative_errors(gt, gt);
  EXPECT_THROW(compare_relative_errors(a, b), InputError);
  // The baseline equal to the ground truth: all its errors are 0.
  const RelativeErrors c = compute_relative_errors(gt, with_step_noise(gt, 1e-3, 1e-3, 1));
  EXPECT_THROW(compare_relative_errors(c, b), InputError);
}

}  // namespace
}  // namespace jpcr
