// The tracker: ICP-ftf along the synthetic drift rig (rail, 10 mm per frame, noise-free), the
// keyframe policy, and a failed frame that keeps the last good motion and says so.
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/frontend/keyframe_tracker.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/io/trajectory_metrics.hpp"
#include "jpcr/quadric/error.hpp"
#include "synthetic_views.hpp"

namespace jpcr {
namespace {

SyntheticSequence rail(int frames) {
  SyntheticSequenceOptions options;
  options.scene = "rail_wall";
  options.trajectory = TrajectoryKind::kRail;
  options.frames = frames;
  return make_synthetic_sequence(options);
}

// A 160x120 walk through `scene`.
SyntheticSequenceOptions small_walk(const std::string& scene, int frames, std::uint64_t seed) {
  SyntheticSequenceOptions options;
  options.scene = scene;
  options.frames = frames;
  options.width = 160;
  options.height = 120;
  options.seed = seed;
  return options;
}

Trajectory track_all(const FrameSource& source, KeyframeTracker& tracker,
                     std::vector<TrackResult>* results = nullptr) {
  Trajectory estimate;
  for (std::size_t i = 0; i < source.size(); ++i) {
    TrackResult r = tracker.track(source.load(i));
    estimate.push_back(r.T_wc);
    if (results) results->push_back(r);
  }
  return estimate;
}

TEST(KeyframeTracker, RailAtZeroNoiseHasSubMillimetreRpe) {
  // The goal: RPE per frame < 0.5 mm on the noise-free rail.
  const SyntheticSequence seq = rail(16);
  const Trajectory gt = seq.ground_truth_trajectory();
  for (TrackingMode mode : {TrackingMode::frame_to_frame, TrackingMode::frame_to_keyframe}) {
    FrontendParams params;
    params.tracker.mode = mode;
    KeyframeTracker tracker(params, gt.front().pose);
    std::vector<TrackResult> results;
    const Trajectory est = track_all(seq, tracker, &results);
    for (const TrackResult& r : results) {
      if (r.index == 0) continue;
      EXPECT_EQ(r.icp.verdict, IcpVerdict::ok) << to_string(mode) << " frame " << r.index;
      EXPECT_FALSE(r.kept_last_motion);
    }
    const RpeResult rpe = compute_rpe(gt, est, 1.0, DeltaUnit::kFrames);
    EXPECT_LT(rpe.translation.rmse, 0.5e-3) << to_string(mode);
    EXPECT_LT(rpe.rotation.rmse, 0.05) << to_string(mode);  // deg
    RecordProperty(std::string("rpe_mm_") + to_string(mode),
                   std::to_string(rpe.translation.rmse * 1e3));
    std::printf("%s: RPE per frame %.4f mm, %.5f deg\n", to_string(mode),
                rpe.translation.rmse * 1e3, rpe.rotation.rmse);
  }
}

TEST(KeyframeTracker, KeyframesFollowTheTranslationThreshold) {
  const SyntheticSequence seq = rail(16);
  FrontendParams params;
  params.tracker.keyframe_translation = 0.045;  // m: the rail moves 10 mm per frame
  params.tracker.keyframe_overlap = 0.0;
  KeyframeTracker tracker(params, seq.ground_truth(0).value());
  track_all(seq, tracker);
  EXPECT_EQ(tracker.keyframe_indices(), (std::vector<int>{0, 5, 10, 15}));
  EXPECT_EQ(tracker.keyframe().index, 15);
  EXPECT_NEAR(tracker.keyframe().T_wc.timestamp, seq.timestamp(15), 1e-9);
  EXPECT_EQ(tracker.keyframe().pyramid->levels.size(), 3u);
}

// The overlap of the keyframe policy measures the view the frame shares with the keyframe, so
// depth noise leaves it as it is (it used to count the pairs that passed the ICP rejection tests:
// at 1 % range noise every 640x480 frame became a keyframe).
TEST(KeyframeTracker, OverlapIsTheSharedViewNotTheDepthNoise) {
  std::vector<double> overlap[2];
  for (int noisy = 0; noisy < 2; ++noisy) {
    SyntheticSequenceOptions o = small_walk("room_spheres", 8, 5);
    o.noise = noisy ? "range:2" : "none";
    const SyntheticSequence seq = make_synthetic_sequence(o);
    FrontendParams params;
    params.threads = 2;
    params.tracker.mode = TrackingMode::frame_to_keyframe;
    params.tracker.keyframe_translation = 1.0;  // the overlap alone decides
    params.tracker.keyframe_rotation = 90.0;
    KeyframeTracker tracker(params, seq.ground_truth(0).value());
    std::vector<TrackResult> results;
    track_all(seq, tracker, &results);
    for (const TrackResult& r : results)
      if (r.index > 0) overlap[noisy].push_back(r.overlap);
  }
  ASSERT_EQ(overlap[0].size(), 7u);  // frames 1..7, each with an overlap
  ASSERT_EQ(overlap[1].size(), 7u);
  for (std::size_t i = 0; i < overlap[0].size(); ++i) {
    EXPECT_GT(overlap[0][i], 0.8) << "frame " << i + 1;  // a walk of 7 frames (0.23 s)
    EXPECT_NEAR(overlap[1][i], overlap[0][i], 0.05) << "frame " << i + 1;
  }
}

// Tracks the 5 frames of `seq` (the rail) with frame 3's depth all `depth_3` (m).
std::vector<TrackResult> track_with_frame_3_at(const SyntheticSequence& seq, float depth_3) {
  KeyframeTracker tracker(FrontendParams{}, seq.ground_truth(0).value());
  std::vector<TrackResult> results;
  for (std::size_t i = 0; i < 5; ++i) {
    Frame f = seq.load(i);
    if (i == 3) f.depth = DepthImage(f.depth.width(), f.depth.height(), depth_3);
    results.push_back(tracker.track(f));
  }
  return results;
}

TEST(KeyframeTracker, AFailedFrameKeepsTheLastGoodMotion) {
  const SyntheticSequence seq = rail(5);
  const std::vector<TrackResult> results = track_with_frame_3_at(seq, 0.0f);  // a blackout
  EXPECT_EQ(results[3].icp.verdict, IcpVerdict::too_few_points);
  EXPECT_TRUE(results[3].kept_last_motion);
  // Constant velocity through the gap: 10 mm further along the rail.
  const Eigen::Isometry3d gt3 = seq.ground_truth(3).value();
  EXPECT_LT(test::translation_error(results[3].T_wc.pose, gt3), 1e-3);
  // The next frame aligns with the last one that has points, frame 2, not with the blank one
  // (it failed against the blank one and kept the extrapolated motion): measured, and trusted.
  ASSERT_EQ(FrontendParams{}.tracker.mode, TrackingMode::frame_to_frame);
  EXPECT_EQ(results[4].reference, 2);
  EXPECT_EQ(results[4].icp.verdict, IcpVerdict::ok) << to_string(results[4].icp.verdict);
  EXPECT_FALSE(results[4].kept_last_motion);
  const Eigen::Isometry3d step = results[2].T_wc.pose.inverse() * results[4].T_wc.pose;
  const Eigen::Isometry3d true_step =
      seq.ground_truth(2).value().inverse() * seq.ground_truth(4).value();
  std::printf("frame 4: %.3g mm from the truth, its step from frame 2 %.3g mm\n",
              1e3 * test::translation_error(results[4].T_wc.pose, seq.ground_truth(4).value()),
              1e3 * test::translation_error(step, true_step));
  EXPECT_LT(test::translation_error(step, true_step), 1e-4);
  // Its covariance goes on from frame 2's, not from the blank frame's guess.
  EXPECT_LT(results[4].pose_covariance.trace(), results[3].pose_covariance.trace());
  // A failed alignment starts a keyframe, so that the back end refines the extrapolated motion;
  // but not the blank frame, which has no points.
  EXPECT_FALSE(results[3].is_keyframe);
  EXPECT_FALSE(results[2].is_keyframe);  // 20 mm along the rail: not by distance
}

// A wall 1 m ahead in every fourth frame: it fails and, having points, becomes the reference, so
// the next frame fails too; each failure composes the kept motion again. Isometry3d's inverse
// transposes, so without re-orthonormalising the error of the rotations grew some 5x per cycle
// (2.5e-9 after these 20 failures; the next alignment refuses a guess past 1e-6).
TEST(KeyframeTracker, RotationsStayOrthonormalThroughRepeatedFailures) {
  const SyntheticSequence seq = make_synthetic_sequence(small_walk("room_spheres", 41, 3));
  KeyframeTracker tracker(FrontendParams{}, seq.ground_truth(0).value());
  double worst = 0.0;
  int kept = 0;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    Frame f = seq.load(i);
    if (i % 4 == 1) f.depth = DepthImage(f.depth.width(), f.depth.height(), 1.0f);
    const TrackResult r = tracker.track(f);
    kept += r.kept_last_motion ? 1 : 0;
    const Eigen::Matrix3d R = r.T_wc.pose.linear();
    worst =
        std::max(worst, (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
  }
  EXPECT_EQ(kept, 20);
  EXPECT_LT(worst, 1e-12);
}

// Frame to frame, a failed alignment of a frame that has points starts a keyframe, so that the
// back end refines the extrapolated motion: frame 3 sees a wall 1 m ahead instead of the rail's
// scene (a person stepping in front of the camera), nothing pairs with frame 2 within the gate.
TEST(KeyframeTracker, AFailedAlignmentOfAFrameWithPointsStartsAKeyframe) {
  const std::vector<TrackResult> results = track_with_frame_3_at(rail(5), 1.0f);
  EXPECT_NE(results[3].icp.verdict, IcpVerdict::ok) << to_string(results[3].icp.verdict);
  EXPECT_TRUE(results[3].kept_last_motion);
  EXPECT_TRUE(results[3].is_keyframe);
  EXPECT_FALSE(results[2].is_keyframe);  // 20 mm along the rail: not by distance
}

// Frame to frame, a degenerate alignment (a featureless corridor) keeps the last motion but
// starts no keyframe, or every frame of such a view would be one; J-ftf could not observe the
// motion either.
TEST(KeyframeTracker, ADegenerateAlignmentStartsNoKeyframeFrameToFrame) {
  const SyntheticSequence seq = make_synthetic_sequence(small_walk("corridor", 5, 1));
  KeyframeTracker tracker(FrontendParams{}, seq.ground_truth(0).value());
  int degenerate = 0;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const TrackResult r = tracker.track(seq.load(i));
    if (i == 0 || r.icp.verdict != IcpVerdict::degenerate) continue;
    ++degenerate;
    EXPECT_TRUE(r.kept_last_motion) << "frame " << i;
    EXPECT_FALSE(r.is_keyframe) << "frame " << i;
  }
  EXPECT_GE(degenerate, 3);
}

// The pose covariance is zero for the gauge and grows along the chain: each frame's is its
// reference's plus its alignment's carried into world axes; a frame that kept the last motion
// adds the last good alignment's again.
TEST(KeyframeTracker, PoseCovarianceAccumulatesAlongTheChainOfAlignments) {
  const SyntheticSequence seq = rail(5);
  FrontendParams params;
  params.tracker.mode = TrackingMode::frame_to_frame;
  KeyframeTracker tracker(params, seq.ground_truth(0).value());
  std::vector<TrackResult> r;
  for (std::size_t i = 0; i < 5; ++i) {
    Frame f = seq.load(i);
    if (i == 4) f.depth = DepthImage(f.depth.width(), f.depth.height(), 0.0f);  // blackout
    r.push_back(tracker.track(f));
  }
  EXPECT_EQ(r[0].pose_covariance, Matrix6d::Zero());
  for (std::size_t i = 1; i < 5; ++i) {
    const Matrix6d step = r[i].pose_covariance - r[i - 1].pose_covariance;
    const Matrix6d& icp = i < 4 ? r[i].icp.covariance : r[3].icp.covariance;
    const Matrix6d Ad = se3_adjoint(r[i - 1].T_wc.pose);
    EXPECT_LT((step - Ad * icp * Ad.transpose()).norm(), 1e-9 * step.norm()) << "frame " << i;
    EXPECT_GT(step.trace(), 0.0) << "frame " << i;
    // Carried into world axes, not added in the camera's: the trace of the rotation block is
    // kept, the translation block gains the lever arm of the rotation.
    const double rotation_in_world = step.bottomRightCorner<3, 3>().trace();
    const double rotation_in_camera = icp.bottomRightCorner<3, 3>().trace();
    EXPECT_NEAR(rotation_in_world, rotation_in_camera, 1e-9 * icp.trace());
  }
  EXPECT_TRUE(r[4].kept_last_motion);

  // Against the keyframe (frame 0 here), frame 3's alignment covariance Σ is in the keyframe's
  // axes: the blackout repeats frame 3's step from frame 3, so it adds Σ carried from the
  // keyframe to frame 2 (the step's start), then from frame 3 into map axes (it added Σ as if in
  // frame 3's own axes before).
  params.tracker.mode = TrackingMode::frame_to_keyframe;
  KeyframeTracker to_keyframe(params, seq.ground_truth(0).value());
  std::vector<TrackResult> k;
  for (std::size_t i = 0; i < 5; ++i) {
    Frame f = seq.load(i);
    if (i == 4) f.depth = DepthImage(f.depth.width(), f.depth.height(), 0.0f);
    k.push_back(to_keyframe.track(f));
  }
  ASSERT_EQ(k[3].reference, 0);
  ASSERT_TRUE(k[4].kept_last_motion);
  const Matrix6d step = k[4].pose_covariance - k[3].pose_covariance;
  const Matrix6d Ad = se3_adjoint(k[3].T_wc.pose * k[2].T_wc.pose.inverse() * k[0].T_wc.pose);
  const Matrix6d expected = Ad * k[3].icp.covariance * Ad.transpose();
  EXPECT_LT((step - expected).norm(), 1e-9 * expected.norm());
}

// A blackout before any alignment succeeded: the frame keeps the (identity) motion, and its pose
// is as unknown as a motion can be, 1 m / 1 rad per axis carried into world axes, not the zero
// covariance of the gauge (odom would claim a perfectly known pose).
TEST(KeyframeTracker, ABlackoutBeforeAnyAlignmentIsAnUnknownMotion) {
  const SyntheticSequence seq = rail(2);
  const Eigen::Isometry3d start = seq.ground_truth(0).value();
  KeyframeTracker tracker(FrontendParams{}, start);
  const TrackResult first = tracker.track(seq.load(0));
  Frame blank = seq.load(1);
  blank.depth = DepthImage(blank.depth.width(), blank.depth.height(), 0.0f);
  const TrackResult r = tracker.track(blank);
  EXPECT_EQ(first.pose_covariance, Matrix6d::Zero());
  EXPECT_TRUE(r.kept_last_motion);
  EXPECT_TRUE(r.T_wc.pose.isApprox(start, 1e-12));
  const Matrix6d Ad = se3_adjoint(start);
  EXPECT_LT((r.pose_covariance - Ad * Ad.transpose()).norm(), 1e-12);
}

// A sensor that starts blank: the frames before the first with points have nothing to be
// aligned to and stay at the initial pose, unknown; the first frame with points is keyframe 0,
// the gauge, exact; the next one aligns with it.
TEST(KeyframeTracker, ABlankStartMovesTheGaugeToTheFirstFrameWithPoints) {
  const SyntheticSequence seq = rail(4);
  const Eigen::Isometry3d start = seq.ground_truth(0).value();
  KeyframeTracker tracker(FrontendParams{}, start);
  std::vector<TrackResult> r;
  for (std::size_t i = 0; i < 4; ++i) {
    Frame f = seq.load(i);
    if (i < 2) f.depth = DepthImage(f.depth.width(), f.depth.height(), 0.0f);
    r.push_back(tracker.track(f));
    EXPECT_EQ(tracker.has_keyframe(), i >= 2) << "frame " << i;
  }
  const Matrix6d Ad = se3_adjoint(start);
  for (int i = 0; i < 2; ++i) {
    EXPECT_FALSE(r[i].is_keyframe);
    EXPECT_FALSE(r[i].is_gauge);
    EXPECT_TRUE(r[i].kept_last_motion);
    EXPECT_EQ(r[i].reference, -1);
    EXPECT_EQ(r[i].icp.verdict, IcpVerdict::too_few_points);
    EXPECT_TRUE(r[i].T_wc.pose.isApprox(start, 0.0));
    EXPECT_LT((r[i].pose_covariance - Ad * Ad.transpose()).norm(), 1e-12);
  }
  EXPECT_TRUE(r[2].is_keyframe);
  EXPECT_TRUE(r[2].is_gauge);
  EXPECT_FALSE(r[2].kept_last_motion);
  EXPECT_EQ(r[2].reference, -1);
  EXPECT_TRUE(r[2].T_wc.pose.isApprox(start, 0.0));
  EXPECT_EQ(r[2].pose_covariance, Matrix6d::Zero());
  EXPECT_EQ(tracker.keyframe_indices(), std::vector<int>{2});
  EXPECT_EQ(r[3].reference, 2);
  EXPECT_EQ(r[3].icp.verdict, IcpVerdict::ok) << to_string(r[3].icp.verdict);
  // As a tracker started at frame 2 tracks frame 3, to the bit.
  KeyframeTracker late(FrontendParams{}, start);
  late.track(seq.load(2));
  const TrackResult late_3 = late.track(seq.load(3));
  EXPECT_TRUE(r[3].T_wc.pose.isApprox(late_3.T_wc.pose, 0.0));
  EXPECT_EQ(r[3].pose_covariance, late_3.pose_covariance);
}

TEST(KeyframeTracker, WrongSizedFrameIsAnInputError) {
  KeyframeTracker tracker;
  Frame f;
  f.camera = synthetic_camera(64, 48);
  f.depth = DepthImage(48, 64, 1.0f);
  EXPECT_THROW(tracker.track(f), InputError);
  EXPECT_FALSE(tracker.has_keyframe());
  EXPECT_THROW(tracker.keyframe(), std::logic_error);
}

// A frame from another camera (here a resized stream) is refused before the tracker counts it,
// so the next frame of the first camera is tracked as if it never came.
TEST(KeyframeTracker, AFrameFromAnotherCameraIsRefusedAndTrackingGoesOn) {
  const SyntheticSequence seq = rail(3);
  KeyframeTracker tracker(FrontendParams{}, seq.ground_truth(0).value());
  tracker.track(seq.load(0));
  Frame other = seq.load(1);
  other.camera = other.camera.resized(other.camera.width / 2, other.camera.height / 2);
  other.depth = DepthImage(other.camera.width, other.camera.height, 1.0f);
  const std::string error = test::input_error_of([&] { tracker.track(other); });
  EXPECT_NE(error.find("frame 1"), std::string::npos) << error;
  EXPECT_NE(error.find("camera"), std::string::npos) << error;
  const TrackResult r = tracker.track(seq.load(1));
  EXPECT_EQ(r.index, 1);
  EXPECT_EQ(r.icp.verdict, IcpVerdict::ok);
  EXPECT_LT(test::translation_error(r.T_wc.pose, seq.ground_truth(1).value()), 0.5e-3);
}

TEST(KeyframeTracker, InvalidParamsAreRejected) {
  FrontendParams params;
  params.icp.iterations = {0, 0, 0};
  EXPECT_THROW(KeyframeTracker{params}, InputError);
}

// An initial pose that is no rigid motion (an unnormalised quaternion's R, scaled by 1 + 1e-5) is
// refused at once: it was taken, and every frame after the first then threw.
TEST(KeyframeTracker, AnInitialPoseThatIsNoRigidMotionIsRefused) {
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 1.0 + 1e-5;
  EXPECT_EQ(test::input_error_of([&] { KeyframeTracker tracker({}, scaled); }),
            "initial_pose: must be a rigid motion (finite, R orthonormal, det R = 1)");
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(KeyframeTracker({}, nan), InputError);
}

}  // namespace
}  // namespace jpcr
