// ICP-ftf on exact synthetic pairs: the known motion is recovered, a plane is degenerate, no
// overlap is never `ok`, and bad frames give verdicts, not crashes.
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "jpcr/frontend/point_to_plane_icp.hpp"
#include "jpcr/io/synthetic_noise.hpp"
#include "jpcr/quadric/error.hpp"
#include "synthetic_views.hpp"

namespace jpcr {
namespace {

using test::kDeg;

struct Pair {
  FramePyramid source, target;
  Eigen::Isometry3d truth;  // source → target
};

// The target at T_wt and the source moved by `delta` in the target's frame.
Pair render_pair(const SyntheticScene& scene, const Eigen::Isometry3d& T_wt,
                 const Eigen::Isometry3d& delta) {
  return {preprocess(test::render_at(scene, T_wt * delta)),
          preprocess(test::render_at(scene, T_wt)), delta};
}

// The free functions are a library's entry points: parameters the YAML loader would refuse are
// refused there too, not divided by (a level-0 stride of 0 ended the process with SIGFPE).
TEST(PointToPlaneIcp, RefusesParametersItsValidateRefuses) {
  const Pair pair = render_pair(test::room(), test::room_view(), test::motion(0.02, 2.0 * kDeg));
  IcpParams no_stride;
  no_stride.level0_stride = 0;
  EXPECT_THROW(align_point_to_plane(pair.source, pair.target, pair.truth, no_stride), InputError);
  EXPECT_THROW(linearize_point_to_plane(pair.source, pair.target, 0, pair.truth, IcpParams{}, 0),
               InputError);
  // A guess that is no rigid motion, and a pyramid deeper than the iterations are given for
  // (they were indexed past their end).
  Eigen::Isometry3d scaled = pair.truth;
  scaled.linear() *= 2.0;
  EXPECT_THROW(align_point_to_plane(pair.source, pair.target, scaled, IcpParams{}), InputError);
  FramePyramid deep = pair.source;
  deep.levels.push_back(deep.levels.back());
  EXPECT_THROW(align_point_to_plane(deep, pair.target, pair.truth, IcpParams{}), InputError);
  PreprocessParams no_offset;
  no_offset.normal_offset = 0;
  EXPECT_THROW(preprocess(test::render_at(test::room(), test::room_view()), no_offset), InputError);
}

TEST(PointToPlaneIcp, RecoversAKnownMotionOnNoiseFreeData) {
  // 2 cm and 2° (the case), noise-free: within 0.1 mm and 0.01°.
  const Pair pair = render_pair(test::room(), test::room_view(), test::motion(0.02, 2.0 * kDeg));
  IcpParams params;
  params.iterations = {10, 10, 10};
  const IcpResult r =
      align_point_to_plane(pair.source, pair.target, Eigen::Isometry3d::Identity(), params);
  EXPECT_EQ(r.verdict, IcpVerdict::ok) << to_string(r.verdict);
  EXPECT_LT(test::translation_error(r.pose, pair.truth), 1e-4);
  EXPECT_LT(test::rotation_error(r.pose, pair.truth), 0.01 * kDeg);
  std::printf("2 cm, 2 deg: error %.2e m, %.2e deg after %d iterations\n",
              test::translation_error(r.pose, pair.truth),
              test::rotation_error(r.pose, pair.truth) / kDeg, r.iterations);
  EXPECT_GT(r.inlier_ratio, 0.8);
  EXPECT_LT(r.rms, 1e-3);
  EXPECT_GT(r.degeneracy, params.degeneracy_threshold);
  EXPECT_TRUE(r.eigenvalues.allFinite());
  // The covariance is symmetric positive definite and tiny for exact data.
  EXPECT_LT((r.covariance - r.covariance.transpose()).norm(), 1e-12 * r.covariance.norm());
  EXPECT_GT(r.covariance.ldlt().vectorD().minCoeff(), 0.0);
  EXPECT_LT(r.covariance.diagonal().head<3>().maxCoeff(), 1e-8);  // σ_t < 0.1 mm
}

// The covariance σ² (JᵀWJ)⁻¹ describes the spread over noise draws whatever the weights' scale:
// with the default z⁻⁴ depth weights Σ w is not the number of residuals, and σ² must be the
// variance of a unit-weight residual, Σ w e² / (n − 6). 16 draws of a 320x240 room pair at range
// noise 0.3 %; a sample sd from 16 draws scatters by about ±18 %, so the band is [0.5, 2].
TEST(PointToPlaneIcp, CovarianceMatchesTheSpreadOverNoiseDraws) {
  const Eigen::Isometry3d T_wt = test::room_view();
  const Eigen::Isometry3d delta = test::motion(0.01, 0.5 * kDeg);
  const CameraIntrinsics camera = synthetic_camera(320, 240);
  const NoiseModel noise = parse_noise("range:0.3");
  const int draws = 16;
  std::vector<Vector6d> errors;
  Matrix6d predicted = Matrix6d::Zero();
  for (int seed = 1; seed <= draws; ++seed) {
    const FramePyramid source =
        preprocess(render(test::room(), camera, T_wt * delta, noise, seed, 1).frame);
    const FramePyramid target =
        preprocess(render(test::room(), camera, T_wt, noise, seed, 2).frame);
    const IcpResult r = align_point_to_plane(source, target, Eigen::Isometry3d::Identity());
    ASSERT_EQ(r.verdict, IcpVerdict::ok) << to_string(r.verdict);
    errors.push_back(se3_log(r.pose * delta.inverse()));  // the left update's coordinates
    predicted += r.covariance / draws;
  }
  Vector6d mean = Vector6d::Zero();
  for (const Vector6d& e : errors)
    mean += e / draws;
  for (int i = 0; i < 6; ++i) {
    double spread = 0.0;
    for (const Vector6d& e : errors)
      spread += (e[i] - mean[i]) * (e[i] - mean[i]) / (draws - 1);
    const double ratio = std::sqrt(spread / predicted(i, i));
    std::printf("axis %d: sd of the errors / predicted sd = %.2f\n", i, ratio);
    EXPECT_GT(ratio, 0.5) << "axis " << i;
    EXPECT_LT(ratio, 2.0) << "axis " << i;
  }
}

// The z⁻ᵏ depth weights must not bias the alignment: taken from the target's noisy depth alone,
// a weight is correlated with the residual and E[w e] / E[w] ≈ −k σ² / z shifted every alignment
// along the view; with the mean of the pair's two depths the two frames' terms cancel (review of
// 2026-12-06). Both frames at the same pose, independent 1 % range noise, 320x240: one draw's
// error along the camera's z scatters by about 0.32 mm, so the mean of 24 by 0.065 mm. Measured
// over these 24 draws: −0.67 mm with the target's depth, −0.15 mm with the mean (30 other draws:
// −0.08, and −0.03 without depth weights). The bound 0.3 mm is 2.3 standard errors above the mean
// now and 5.7 below the biased one.
TEST(PointToPlaneIcp, TheDepthWeightsDoNotShiftTheAlignmentAlongTheView) {
  const Eigen::Isometry3d T_wt = test::room_view();
  const CameraIntrinsics camera = synthetic_camera(320, 240);
  const NoiseModel noise = parse_noise("range:1");
  constexpr int kDraws = 24;
  double mean_z = 0.0;
  for (int seed = 1; seed <= kDraws; ++seed) {
    const FramePyramid source =
        preprocess(render(test::room(), camera, T_wt, noise, seed, 1).frame);
    const FramePyramid target =
        preprocess(render(test::room(), camera, T_wt, noise, seed, 2).frame);
    const IcpResult r = align_point_to_plane(source, target, Eigen::Isometry3d::Identity());
    ASSERT_EQ(r.verdict, IcpVerdict::ok) << to_string(r.verdict);
    mean_z += r.pose.translation().z() / kDraws;
  }
  std::printf("mean translation error along the view: %.3f mm\n", 1e3 * mean_z);
  EXPECT_LT(std::abs(mean_z), 0.3e-3);
}

TEST(PointToPlaneIcp, DefaultScheduleRecoversTheMotionToo) {
  const Pair pair = render_pair(test::room(), test::room_view(), test::motion(0.02, 2.0 * kDeg));
  const IcpResult r = align_point_to_plane(pair.source, pair.target, Eigen::Isometry3d::Identity());
  EXPECT_EQ(r.verdict, IcpVerdict::ok) << to_string(r.verdict);
  std::printf("default schedule: error %.2e m, %.2e deg after %d iterations\n",
              test::translation_error(r.pose, pair.truth),
              test::rotation_error(r.pose, pair.truth) / kDeg, r.iterations);
  EXPECT_LT(test::translation_error(r.pose, pair.truth), 2e-4);
  EXPECT_LT(test::rotation_error(r.pose, pair.truth), 0.02 * kDeg);
}

// `converged` means the last step is within the estimate's noise (one standard deviation): four
// steps at the finest level get there on a noisy pair; one step from 2 cm / 2° off does not.
TEST(PointToPlaneIcp, ConvergedMeansTheLastStepIsWithinTheNoise) {
  const Eigen::Isometry3d T_wt = test::room_view();
  const Eigen::Isometry3d delta = test::motion(0.01, 0.5 * kDeg);
  const CameraIntrinsics camera = synthetic_camera(320, 240);
  const NoiseModel noise = parse_noise("range:0.3");
  const FramePyramid source =
      preprocess(render(test::room(), camera, T_wt * delta, noise, 3, 1).frame);
  const FramePyramid target = preprocess(render(test::room(), camera, T_wt, noise, 3, 2).frame);
  IcpParams four;  // the default's 2 steps at the finest level end 1-2 sigma short on this pair
  four.iterations = {4, 2, 5};
  four.min_step_translation = 0.0f;  // only the statistical rule can say converged
  four.min_step_rotation = 0.0f;
  const IcpResult full = align_point_to_plane(source, target, Eigen::Isometry3d::Identity(), four);
  EXPECT_EQ(full.verdict, IcpVerdict::ok) << to_string(full.verdict);
  EXPECT_TRUE(full.converged);
  IcpParams one_step;
  one_step.iterations = {1, 0, 0};
  const Eigen::Isometry3d far = test::motion(0.02, 2.0 * kDeg) * delta;
  const IcpResult cut = align_point_to_plane(source, target, far, one_step);
  EXPECT_FALSE(cut.converged);
  EXPECT_LT(test::translation_error(cut.pose, delta), test::translation_error(far, delta));
}

// Gauss-Newton near the solution of a large motion (15 cm, 12°) converges fast only with the
// Jacobian of the left update T ← exp(ξ^) T: three steps from 2.7 mm / 0.15° off end 1.2e-6 m
// from the fixed point; applied on the right (T ← T exp(ξ^)), 2.3e-5 m (measured). A 2 cm motion
// cannot tell them apart: both sides then differ by about 3 %.
TEST(PointToPlaneIcp, GaussNewtonConvergesFastNearALargeMotion) {
  const Pair pair = render_pair(test::room(), test::room_view(), test::motion(0.15, 12.0 * kDeg));
  IcpParams p;
  p.level0_stride = 1;
  p.min_step_translation = 0.0f;  // exactly the asked-for steps
  p.min_step_rotation = 0.0f;
  const Eigen::Isometry3d start = test::motion(0.0027, 0.15 * kDeg) * pair.truth;
  p.iterations = {30, 0, 0};
  const Eigen::Isometry3d fixed = align_point_to_plane(pair.source, pair.target, start, p).pose;
  p.iterations = {3, 0, 0};
  const IcpResult three = align_point_to_plane(pair.source, pair.target, start, p);
  const double dt = test::translation_error(three.pose, fixed);
  std::printf(
      "3 steps from 2.7 mm, 0.15 deg off a 15 cm, 12 deg motion: %.2e m, %.2e deg from "
      "the fixed point, which is %.2e m from the truth\n",
      dt, test::rotation_error(three.pose, fixed) / kDeg,
      test::translation_error(fixed, pair.truth));
  EXPECT_LT(dt, 5e-6);
  EXPECT_LT(test::translation_error(fixed, pair.truth), 1e-4);
}

TEST(PointToPlaneIcp, HolesInTheDepthDoNotPoisonTheSums) {
  // Real sensors drop pixels: every 7th pixel of both frames has no depth. A full-resolution
  // vertex may then be missing where the borrowed coarser normal exists.
  const Eigen::Isometry3d truth = test::motion(0.02, 2.0 * kDeg);
  Frame source = test::render_at(test::room(), test::room_view() * truth);
  Frame target = test::render_at(test::room(), test::room_view());
  for (std::size_t i = 0; i < source.depth.size(); i += 7) {
    source.depth[i] = 0.0f;
    target.depth[(i + 3) % target.depth.size()] = std::numeric_limits<float>::quiet_NaN();
  }
  const IcpResult r =
      align_point_to_plane(preprocess(source), preprocess(target), Eigen::Isometry3d::Identity());
  EXPECT_EQ(r.verdict, IcpVerdict::ok) << to_string(r.verdict);
  EXPECT_TRUE(std::isfinite(r.rms));
  EXPECT_LT(test::translation_error(r.pose, truth), 2e-4);
  EXPECT_LT(test::rotation_error(r.pose, truth), 0.02 * kDeg);
}

TEST(PointToPlaneIcp, InvariantToTheInitialGuessDirection) {
  // Starting from the truth, it stays there.
  const Pair pair = render_pair(test::room(), test::room_view(), test::motion(0.02, 2.0 * kDeg));
  const IcpResult r = align_point_to_plane(pair.source, pair.target, pair.truth);
  EXPECT_EQ(r.verdict, IcpVerdict::ok);
  EXPECT_LT(test::translation_error(r.pose, pair.truth), 1e-4);
  EXPECT_LT(test::rotation_error(r.pose, pair.truth), 0.01 * kDeg);
}

// Noise in the per-pixel normals used to make a plane look observable: degeneracy 0.0035 at
// range noise 0.25 %, 0.0037 under Kinect noise and 0.024 at 1 % (a room reads 0.011 at 1 %).
// describe() takes the normals' expected noise term out of JᵀWJ, with σ² from the pairs' own
// normal disagreement; the room under the same noise stays observed (measured 1.03e-2). At
// 640x480 the finest level's normals are too noisy for that correction (the wall below read
// 3.2e-3 at 1 %, ok): the verdict takes the finest level whose normals the correction holds
// for, here the coarsest, which sees the plane (0) and the room (9.9e-3) as they are.
TEST(PointToPlaneIcp, ASinglePlaneWithNoisyNormalsIsStillDegenerate) {
  SyntheticScene plane;
  plane.surfaces = {Plane{Eigen::Vector3d(0, 2, 0), Eigen::Vector3d(0, -1, 0)}};
  const Eigen::Isometry3d delta = test::motion(0.01, 1.0 * kDeg);
  for (const int width : {320, 640}) {
    // At 640 px the wall 1.5 m ahead (configs/scenes/single_plane.yaml): seen obliquely from
    // 2.3 m, too few pairs pass the normal test at 1 % to judge the motion (too_few_points).
    const Eigen::Isometry3d T_wt = width == 320 ? test::look_from({0, 0, 1}, {0.3, 2, 1.1})
                                                : test::look_from({0, 0.5, 1}, {0, 2, 1});
    const CameraIntrinsics camera = synthetic_camera(width, width * 3 / 4);
    const auto noisy = [&](const SyntheticScene& scene, const Eigen::Isometry3d& T_wc,
                           const char* noise, std::uint64_t frame) {
      return preprocess(render(scene, camera, T_wc, parse_noise(noise), 7, frame).frame);
    };
    for (const char* noise : {"range:0.25", "range:1", "kinect"}) {
      const IcpResult r =
          align_point_to_plane(noisy(plane, T_wt * delta, noise, 1), noisy(plane, T_wt, noise, 0),
                               Eigen::Isometry3d::Identity());
      std::printf("plane, %d px, %s: %s, degeneracy %.3g\n", width, noise, to_string(r.verdict),
                  r.degeneracy);
      EXPECT_EQ(r.verdict, IcpVerdict::degenerate)
          << width << " px, " << noise << ": " << r.degeneracy;
    }
    const IcpResult room = align_point_to_plane(
        noisy(test::room(), test::room_view() * delta, "range:1", 1),
        noisy(test::room(), test::room_view(), "range:1", 0), Eigen::Isometry3d::Identity());
    std::printf("room, %d px, range:1: %s, degeneracy %.3g\n", width, to_string(room.verdict),
                room.degeneracy);
    EXPECT_EQ(room.verdict, IcpVerdict::ok) << width << " px: " << to_string(room.verdict);
    EXPECT_GT(room.degeneracy, 3.0 * IcpParams{}.degeneracy_threshold) << width << " px";
  }
}

// Noise-free, the finest level's normals need no correction and it answers: a coarse level
// loses small structure (2 cm bumps on a wall at 320x240 read 7.7e-4 at 80x60, 9.8e-4 at full
// size), and taking the smallest over the levels made 26 of 29 good alignments of such a walk
// `degenerate` (ATE 31 mm from the kept motions, 0.96 mm when they were accepted).
TEST(PointToPlaneIcp, NoiseFreeTheVerdictSeesTheFinestLevel) {
  SyntheticScene wall;
  wall.surfaces = {Plane{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, -1, 0)}};
  for (const double x : {-0.6, -0.2, 0.2, 0.6})
    for (const double z : {0.6, 1.0, 1.4})
      wall.surfaces.push_back(Sphere{Eigen::Vector3d(x, 0, z), 0.02});
  const Eigen::Isometry3d T_wt = test::look_from({0, -1.5, 1}, {0, 0, 1});
  const CameraIntrinsics camera = synthetic_camera(320, 240);
  const auto frame = [&](const Eigen::Isometry3d& T_wc) {
    return preprocess(render(wall, camera, T_wc, parse_noise("none"), 1, 0).frame);
  };
  const FramePyramid target = frame(T_wt), source = frame(T_wt * test::motion(0.008, 0.3 * kDeg));
  IcpParams finest_only;
  finest_only.iterations = {9, 0, 0};
  const IcpResult pyramid = align_point_to_plane(source, target, Eigen::Isometry3d::Identity());
  const IcpResult finest =
      align_point_to_plane(source, target, Eigen::Isometry3d::Identity(), finest_only);
  std::printf("bumps: degeneracy %.3g (pyramid), %.3g (finest level only)\n", pyramid.degeneracy,
              finest.degeneracy);
  EXPECT_NEAR(pyramid.degeneracy, finest.degeneracy, 0.05 * finest.degeneracy);
}

TEST(PointToPlaneIcp, ASinglePlaneIsDegenerate) {
  SyntheticScene plane;
  plane.surfaces = {Plane{Eigen::Vector3d(0, 2, 0), Eigen::Vector3d(0, -1, 0)}};
  const Eigen::Isometry3d T_wt = test::look_from({0, 0, 1}, {0.3, 2, 1.1});
  const Pair pair = render_pair(plane, T_wt, test::motion(0.01, 1.0 * kDeg));
  const IcpResult r = align_point_to_plane(pair.source, pair.target, Eigen::Isometry3d::Identity());
  EXPECT_EQ(r.verdict, IcpVerdict::degenerate) << to_string(r.verdict);
  EXPECT_LT(r.degeneracy, 1e-6);  // three directions are unobserved: exactly 0 up to rounding
  EXPECT_GT(r.inlier_ratio, 0.9);
  // The unobserved directions keep the initial guess (the motion is 1 cm).
  EXPECT_LT(test::translation_error(r.pose, pair.truth), 0.012);
  // and the covariance says they are unknown: variance 1 along each of the three (σ² H⁻¹ alone
  // gave millimetres there, from the normals' noise), while what the plane observes stays
  // known (noise-free: far below a millimetre or a milliradian).
  const Vector6d variances = Eigen::SelfAdjointEigenSolver<Matrix6d>(r.covariance).eigenvalues();
  EXPECT_GT(variances[3], 0.5) << variances.transpose();
  EXPECT_LT(variances[2], 1e-6) << variances.transpose();
}

// Along a direction the geometry does not observe, the gradient is the normals' noise: here the
// depth's 0.2 mm steps (a PNG at 5000 per metre). The full Gauss-Newton step moved the pose
// along the corridor by 8.9 mm in the first pair below; on a 10-frame corridor walk at 160x120
// 5 of 9 alignments went past max_translation, `diverged` (a failure: each a keyframe). The step
// now leaves out what is unobserved (observable_step): along the axis the pose keeps the guess.
TEST(PointToPlaneIcp, UnobservedDirectionsKeepTheInitialGuess) {
  const SyntheticScene& corridor = load_scene("corridor");
  const Eigen::Isometry3d T_wt = test::look_from(corridor.view.eye, corridor.view.target);
  const auto quantised = [&](const Eigen::Isometry3d& T_wc) {
    Frame f = render(corridor, synthetic_camera(320, 240), T_wc).frame;
    for (std::size_t i = 0; i < f.depth.size(); ++i)
      f.depth[i] = static_cast<float>(std::round(f.depth[i] * 5000.0) / 5000.0);
    return preprocess(f);
  };
  const FramePyramid target = quantised(T_wt);
  for (const double along : {0.0025, -0.004, 0.01}) {
    Eigen::Isometry3d delta = test::motion(0.002, 0.1 * kDeg);
    delta.translation().z() += along;  // the camera looks along the corridor
    const IcpResult r =
        align_point_to_plane(quantised(T_wt * delta), target, Eigen::Isometry3d::Identity());
    std::printf("corridor, %.4f m: %s, degeneracy %.3g, error %.2f mm\n", along,
                to_string(r.verdict), r.degeneracy, 1e3 * test::translation_error(r.pose, delta));
    std::printf("  sideways error %.3f mm, along the axis %.3f mm\n",
                1e3 * (r.pose.translation().x() - delta.translation().x()),
                1e3 * r.pose.translation().z());
    EXPECT_EQ(r.verdict, IcpVerdict::degenerate) << along;
    // Sideways the walls observe the motion (1.6 mm of it); along the axis nothing does, and
    // the pose keeps the guess's 0 there (up to the coupling of the observed directions).
    EXPECT_NEAR(r.pose.translation().x(), delta.translation().x(), 5e-4) << along;
    EXPECT_NEAR(r.pose.translation().z(), 0.0, 5e-4) << along;
  }
}

TEST(PointToPlaneIcp, NoOverlapIsNotOk) {
  // The camera turned by 180°: nothing the source sees is in the target's view. Given the true
  // motion, the source points land behind the target camera.
  const Eigen::Isometry3d half_turn(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  const Pair pair = render_pair(test::room(), test::room_view(), half_turn);
  const IcpResult truth_start = align_point_to_plane(pair.source, pair.target, pair.truth);
  EXPECT_NE(truth_start.verdict, IcpVerdict::ok) << to_string(truth_start.verdict);
  EXPECT_EQ(truth_start.verdict, IcpVerdict::too_few_points);
  const IcpResult identity_start =
      align_point_to_plane(pair.source, pair.target, Eigen::Isometry3d::Identity());
  EXPECT_NE(identity_start.verdict, IcpVerdict::ok) << to_string(identity_start.verdict);
}

TEST(PointToPlaneIcp, EmptyAndNanFramesGiveVerdictsNotCrashes) {
  const FramePyramid good = preprocess(test::render_at(test::room(), test::room_view()));
  Frame nan_frame;
  nan_frame.camera = synthetic_camera();
  nan_frame.depth = DepthImage(640, 480, std::numeric_limits<float>::quiet_NaN());
  const FramePyramid empty = preprocess(nan_frame);
  EXPECT_EQ(empty.levels[0].valid_vertices, 0u);
  for (const auto& [s, t] : {std::pair(&empty, &good), std::pair(&good, &empty)}) {
    const IcpResult r = align_point_to_plane(*s, *t, Eigen::Isometry3d::Identity());
    EXPECT_EQ(r.verdict, IcpVerdict::too_few_points);
    EXPECT_TRUE(r.pose.matrix().isIdentity());
    // Nothing observed: the covariance of an unknown motion, finite (it goes out on DDS).
    EXPECT_TRUE(r.covariance.allFinite());
    EXPECT_EQ(r.covariance, Matrix6d::Identity());
  }
}

TEST(PointToPlaneIcp, ATooLargeMotionIsDiverged) {
  // A correct 5 cm alignment, but max_translation says no frame moves that far.
  const Pair pair = render_pair(test::room(), test::room_view(), test::motion(0.05, 1.0 * kDeg));
  IcpParams params;
  params.max_translation = 0.03;
  const IcpResult r =
      align_point_to_plane(pair.source, pair.target, Eigen::Isometry3d::Identity(), params);
  EXPECT_EQ(r.verdict, IcpVerdict::diverged) << to_string(r.verdict);
}

// A pyramid assembled by hand without the normals a level needs is refused, not read out of
// bounds (it segfaulted).
TEST(PointToPlaneIcp, APyramidWithoutNormalsIsRefused) {
  FramePyramid frame = preprocess(test::render_at(test::room(), test::room_view(), 64, 48));
  frame.levels.resize(1);  // level 0 borrows level 1's normals, now gone
  IcpParams params;
  params.iterations = {3, 0, 0};
  EXPECT_THROW(align_point_to_plane(frame, frame, Eigen::Isometry3d::Identity(), params),
               InputError);
}

TEST(PointToPlaneIcp, RobustWeights) {
  EXPECT_FLOAT_EQ(robust_weight(0.005f, RobustLoss::huber, 0.01f), 1.0f);
  EXPECT_FLOAT_EQ(robust_weight(-0.04f, RobustLoss::huber, 0.01f), 0.25f);
  EXPECT_FLOAT_EQ(robust_weight(0.0f, RobustLoss::tukey, 0.01f), 1.0f);
  EXPECT_FLOAT_EQ(robust_weight(0.005f, RobustLoss::tukey, 0.01f), 0.5625f);
  EXPECT_FLOAT_EQ(robust_weight(0.02f, RobustLoss::tukey, 0.01f), 0.0f);
  EXPECT_FLOAT_EQ(robust_weight(5.0f, RobustLoss::none, 0.01f), 1.0f);
}

}  // namespace
}  // namespace jpcr
