// The back end's bookkeeping of final frames (pipeline_back_end.hpp): the FrameSink receives
// every frame once, in order, with the pose and verdicts it ends with, and keep_history = false
// gives the same results while holding only the open window. The refiners are stand-ins that
// move the poses by fixed offsets, so that every refinement changes what it touches and the test
// runs in milliseconds (under AddressSanitizer too).
#include <algorithm>
#include <cmath>
#include <new>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/backend/pipeline_back_end.hpp"
#include "jpcr/frontend/frame_pyramid.hpp"

namespace jpcr {
namespace {

// Moves every pose but the gauge by `offset` times its index in the window: a refinement whose
// effect on each keyframe is known and differs between pair and window refiners.
class ShiftingRefiner : public Refiner {
 public:
  ShiftingRefiner(std::string name, Eigen::Vector3d offset)
      : name_(std::move(name)), offset_(std::move(offset)) {}

  RefinementResult refine(const std::vector<Frame>&,
                          const std::vector<Eigen::Isometry3d>& initial) const override {
    RefinementResult r;
    r.report.method = name_;
    r.report.verdict = RefinementVerdict::kConverged;
    for (std::size_t j = 0; j < initial.size(); ++j) {
      Eigen::Isometry3d T = initial[j];
      if (j > 0) T.translation() += static_cast<double>(j) * offset_;
      r.poses.push_back(T);
    }
    r.covariance.assign(initial.size(), Matrix6d::Zero());
    return r;
  }
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics&,
                          const std::vector<Eigen::Isometry3d>& initial,
                          const QuadricMap&) const override {
    return refine(std::vector<Frame>(vertices.size()), initial);
  }
  std::string name() const override { return name_; }
  const JointParams& params() const override { return params_; }

 private:
  std::string name_;
  Eigen::Vector3d offset_;
  JointParams params_;
};

std::unique_ptr<Refiner> shifting(const std::string& name, const JointParams&,
                                  const IcpBundleParams&) {
  return std::make_unique<ShiftingRefiner>(
      name, name == "j-ftf" ? Eigen::Vector3d(1e-3, 0, 0) : Eigen::Vector3d(0, 2e-3, -1e-3));
}

// A refiner that hands everything to `inner` but what a subclass changes.
class WrappingRefiner : public Refiner {
 public:
  explicit WrappingRefiner(std::unique_ptr<Refiner> inner) : inner_(std::move(inner)) {}
  RefinementResult refine(const std::vector<Frame>& frames,
                          const std::vector<Eigen::Isometry3d>& initial) const override {
    return inner_->refine(frames, initial);
  }
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial,
                          const QuadricMap& quadrics) const override {
    return inner_->refine(vertices, camera, initial, quadrics);
  }
  std::string name() const override { return inner_->name(); }
  const JointParams& params() const override { return inner_->params(); }
  bool refines_quadrics() const override { return inner_->refines_quadrics(); }

 private:
  std::unique_ptr<Refiner> inner_;
};

// Records the depth of every frame it is given.
class RecordingRefiner : public WrappingRefiner {
 public:
  RecordingRefiner(std::unique_ptr<Refiner> inner, std::vector<DepthImage>* seen)
      : WrappingRefiner(std::move(inner)), seen_(seen) {}
  RefinementResult refine(const std::vector<Frame>& frames,
                          const std::vector<Eigen::Isometry3d>& initial) const override {
    for (const Frame& f : frames)
      seen_->push_back(f.depth);
    return WrappingRefiner::refine(frames, initial);
  }
  using WrappingRefiner::refine;

 private:
  std::vector<DepthImage>* seen_;
};

// Fails the calls (counted from 0) listed in `fails`: with a failed verdict and the initial
// poses, or by throwing as a refiner out of memory or device does; or (a library caller's broken
// refiner) says it converged with one pose too few, or with a pose that is not finite, or with
// one per-pose verdict too many, or with one pose too few and a usable verdict for it, or throws
// what is no std::exception; or, as Q-full whose poses are independent, fails only the window's
// first or last pose (RefinementReport::pose_verdicts).
class FailingRefiner : public WrappingRefiner {
 public:
  enum class How {
    kVerdict,
    kThrow,
    kOutOfMemory,
    kThrowOther,
    kTooFewPoses,
    kNanPose,
    kTooManyPoseVerdicts,
    kFirstPoseFails,
    kLastPoseFails,
    kPoseVerdictsBeyondThePoses
  };
  FailingRefiner(std::unique_ptr<Refiner> inner, std::vector<int> fails, How how)
      : WrappingRefiner(std::move(inner)), fails_(std::move(fails)), how_(how) {}
  RefinementResult refine(const std::vector<Frame>& frames,
                          const std::vector<Eigen::Isometry3d>& initial) const override {
    if (std::find(fails_.begin(), fails_.end(), calls_++) == fails_.end())
      return WrappingRefiner::refine(frames, initial);
    if (how_ == How::kThrow) throw std::runtime_error("device lost");
    if (how_ == How::kOutOfMemory) throw std::bad_alloc();
    if (how_ == How::kThrowOther) throw 42;
    if (how_ == How::kPoseVerdictsBeyondThePoses) {  // the last pose missing, its verdict not
      RefinementResult r = WrappingRefiner::refine(frames, initial);
      r.poses.pop_back();
      r.report.pose_verdicts.assign(frames.size() - 1, RefinementVerdict::kConverged);
      r.report.pose_verdicts[0] = r.report.verdict = RefinementVerdict::kDiverged;
      return r;
    }
    if (how_ == How::kFirstPoseFails || how_ == How::kLastPoseFails) {
      RefinementResult r = WrappingRefiner::refine(frames, initial);
      const std::size_t bad = how_ == How::kFirstPoseFails ? 1 : r.poses.size() - 1;
      r.report.pose_verdicts.assign(r.poses.size() - 1, RefinementVerdict::kConverged);
      r.report.pose_verdicts[bad - 1] = r.report.verdict = RefinementVerdict::kTooFewQuadrics;
      r.poses[bad] = initial[bad];
      return r;
    }
    RefinementResult r;
    r.report.method = name();
    r.report.verdict = RefinementVerdict::kDiverged;
    r.poses = initial;
    if (how_ == How::kTooFewPoses || how_ == How::kNanPose || how_ == How::kTooManyPoseVerdicts) {
      r = WrappingRefiner::refine(frames, initial);
      if (how_ == How::kTooFewPoses) r.poses.pop_back();
      if (how_ == How::kNanPose) r.poses.back().translation().x() = std::nan("");
      if (how_ == How::kTooManyPoseVerdicts)
        r.report.pose_verdicts.assign(r.poses.size(), RefinementVerdict::kConverged);
    }
    return r;
  }
  using WrappingRefiner::refine;

 private:
  std::vector<int> fails_;
  How how_;
  mutable int calls_ = 0;
};

// Stand-in refiners whose pair (j-ftf) and window calls listed fail as `how` says.
RefinerFactory failing(std::vector<int> pair_fails, std::vector<int> window_fails,
                       FailingRefiner::How how) {
  return [=](const std::string& name, const JointParams& j, const IcpBundleParams& b) {
    return std::make_unique<FailingRefiner>(shifting(name, j, b),
                                            name == "j-ftf" ? pair_fails : window_fails, how);
  };
}

// Keyframe k of a straight walk, 1 cm per keyframe along z.
PipelineFrame walk_frame(int k) {
  PipelineFrame f;
  f.index = k;
  f.front_end.timestamp = 0.1 * k;
  f.front_end.pose = Eigen::Translation3d(0.0, 0.0, 0.01 * k) * Eigen::Isometry3d::Identity();
  return f;
}

// The keyframe's refined motion from the previous one minus the front end's (m).
Eigen::Vector3d correction(const PipelineBackEnd& b, std::size_t k) {
  const PipelineKeyframe &a = b.keyframe(k - 1), &c = b.keyframe(k);
  return (a.refined.pose.inverse() * c.refined.pose).translation() -
         (a.front_end.pose.inverse() * c.front_end.pose).translation();
}

struct Emitted {
  int index = 0;
  StampedPose refined;
  FrameVerdicts verdicts;
};

constexpr int kFrames = 60;
constexpr int kKeyframeEvery = 3;  // frames 0, 3, 6, ... are keyframes
constexpr int kWindow = 4;

// Feeds kFrames tracked frames along a curve; returns what the sink saw, in order.
std::vector<Emitted> run(PipelineMethod method, bool keep_history, std::size_t* max_held,
                         std::unique_ptr<PipelineBackEnd>* out = nullptr) {
  PipelineParams p;
  p.method = method;
  p.window = kWindow;
  p.keep_history = keep_history;
  auto back_end = std::make_unique<PipelineBackEnd>(p, CurvatureSink{}, shifting);
  std::vector<Emitted> emitted;
  back_end->set_frame_sink(
      [&](const PipelineFrame& f, const StampedPose& pose, const FrameVerdicts& v) {
        emitted.push_back({f.index, pose, v});
      });
  const Frame keyframe;  // the stand-in refiners do not look at the depth
  *max_held = 0;
  for (int i = 0; i < kFrames; ++i) {
    PipelineFrame f;
    f.index = i;
    f.front_end.timestamp = 0.033 * i;
    f.front_end.pose = Eigen::Translation3d(0.01 * i, 0.002 * i * i, 0.0) *
                       Eigen::AngleAxisd(0.01 * i, Eigen::Vector3d::UnitY());
    if (i % 7 == 5) f.icp_verdict = IcpVerdict::degenerate;
    const PipelineFrame& added = back_end->add(f, i % kKeyframeEvery == 0 ? &keyframe : nullptr);
    EXPECT_EQ(added.index, i);
    *max_held = std::max(*max_held, back_end->frames().size());
  }
  back_end->finish();
  EXPECT_EQ(back_end->frame_count(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(back_end->keyframe_count(), static_cast<std::size_t>(kFrames / kKeyframeEvery));
  if (out) *out = std::move(back_end);
  return emitted;
}

class PipelineHistory : public ::testing::TestWithParam<PipelineMethod> {};

TEST_P(PipelineHistory, EveryFrameGoesToTheSinkOnceInOrderWithItsFinalPose) {
  std::size_t held = 0;
  std::unique_ptr<PipelineBackEnd> back_end;
  const std::vector<Emitted> emitted = run(GetParam(), true, &held, &back_end);
  ASSERT_EQ(emitted.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(held, static_cast<std::size_t>(kFrames));  // keep_history: everything is held
  const Trajectory end = back_end->trajectory();
  for (int i = 0; i < kFrames; ++i) {
    const Emitted& e = emitted[i];
    EXPECT_EQ(e.index, i);
    // The pose handed over is the one the run ends with: no refinement moved it afterwards.
    EXPECT_TRUE(e.refined.pose.matrix() == end[i].pose.matrix()) << "frame " << i;
    const FrameVerdicts v = back_end->verdicts(i);
    EXPECT_EQ(e.verdicts.front_end, v.front_end) << "frame " << i;
    EXPECT_EQ(e.verdicts.pair, v.pair) << "frame " << i;
    EXPECT_EQ(e.verdicts.window, v.window) << "frame " << i;
  }
}

TEST_P(PipelineHistory, ForgettingFinalFramesGivesTheSameResultsInBoundedMemory) {
  std::size_t held_all = 0, held = 0;
  const std::vector<Emitted> kept = run(GetParam(), true, &held_all, nullptr);
  std::unique_ptr<PipelineBackEnd> back_end;
  const std::vector<Emitted> forgot = run(GetParam(), false, &held, &back_end);
  ASSERT_EQ(forgot.size(), kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(forgot[i].index, kept[i].index);
    EXPECT_TRUE(forgot[i].refined.pose.matrix() == kept[i].refined.pose.matrix()) << i;
    EXPECT_EQ(forgot[i].verdicts.pair, kept[i].verdicts.pair) << i;
    EXPECT_EQ(forgot[i].verdicts.window, kept[i].verdicts.window) << i;
  }
  // An open window spans kWindow keyframes of kKeyframeEvery frames; frames are erased once as
  // many can go as stay, so at most twice that (and the newest frame) is held.
  EXPECT_LE(held, 2u * (kWindow * kKeyframeEvery + 1));
  EXPECT_GT(back_end->first_frame(), 0u);
  EXPECT_GT(back_end->first_keyframe(), 0u);
  EXPECT_THROW(back_end->refined_pose(0), std::out_of_range);
  EXPECT_THROW(back_end->keyframe(0), std::out_of_range);
  EXPECT_THROW(back_end->frame(kFrames), std::out_of_range);
}

INSTANTIATE_TEST_SUITE_P(Methods, PipelineHistory,
                         ::testing::Values(PipelineMethod::kIcpFtf, PipelineMethod::kJointFtf,
                                           PipelineMethod::kJointFull, PipelineMethod::kPipeline),
                         [](const auto& info) {
                           std::string name = to_string(info.param);
                           name.erase(std::remove(name.begin(), name.end(), '-'), name.end());
                           return name;
                         });

// Re-anchoring (pipeline_back_end.hpp): the stand-ins correct keyframes by pure translations, so
// a frame a fraction s of the way from keyframe k to k+1 must be corrected by the translation
// (1 − s) c_k + s c_{k+1} and no rotation; keyframes keep their refined poses; without
// interpolation every frame takes its keyframe's correction c_k. Measured below 1e-14; the 1e-12
// bound also guards the re-orthonormalised keyframe poses: without it the rotation error doubled
// every window, to 2.6e-8 by frame 57.
TEST(PipelineHistory, KeyframeCorrectionsAreSpreadOverTheFramesBetween) {
  double largest_step_in[2] = {0.0, 0.0};  // [interpolate]
  for (const bool interpolate : {true, false}) {
    PipelineParams p;
    p.method = PipelineMethod::kPipeline;
    p.window = kWindow;
    p.interpolate_corrections = interpolate;
    PipelineBackEnd back_end(p, CurvatureSink{}, shifting);
    const Frame keyframe;
    for (int i = 0; i < kFrames; ++i) {
      PipelineFrame f;
      f.index = i;
      f.front_end.pose = Eigen::Translation3d(0.01 * i, 0.002 * i * i, 0.0) *
                         Eigen::AngleAxisd(0.01 * i, Eigen::Vector3d::UnitY());
      back_end.add(f, i % kKeyframeEvery == 0 ? &keyframe : nullptr);
    }
    back_end.finish();
    const auto correction = [](const Eigen::Isometry3d& refined, const Eigen::Isometry3d& front) {
      return Eigen::Isometry3d(refined * front.inverse());
    };
    double largest_step = 0.0, largest_keyframe_step = 0.0;
    for (int i = 0; i < kFrames; ++i) {
      const PipelineFrame& f = back_end.frame(i);
      const Eigen::Isometry3d c = correction(back_end.refined_pose(i).pose, f.front_end.pose);
      EXPECT_LT((c.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-12) << "frame " << i;
      const PipelineKeyframe& k = back_end.keyframe(f.keyframe);
      const Eigen::Vector3d ck = correction(k.refined.pose, k.front_end.pose).translation();
      Eigen::Vector3d expected = ck;
      if (interpolate && static_cast<std::size_t>(f.keyframe) + 1 < back_end.keyframe_count()) {
        const PipelineKeyframe& next = back_end.keyframe(f.keyframe + 1);
        const double s = static_cast<double>(i - k.frame) / (next.frame - k.frame);
        expected =
            (1 - s) * ck + s * correction(next.refined.pose, next.front_end.pose).translation();
      }
      EXPECT_LT((c.translation() - expected).norm(), 1e-12) << "frame " << i;
      if (i == k.frame) {
        EXPECT_TRUE(back_end.refined_pose(i).pose.isApprox(k.refined.pose, 1e-12));
      }
      if (i > 0) {
        const Eigen::Isometry3d before =
            correction(back_end.refined_pose(i - 1).pose, back_end.frame(i - 1).front_end.pose);
        largest_step = std::max(largest_step, (c.translation() - before.translation()).norm());
        if (i == k.frame)
          largest_keyframe_step =
              std::max(largest_keyframe_step, (c.translation() - before.translation()).norm());
      }
    }
    // The refiners move keyframes apart, so the correction changes between keyframes.
    ASSERT_GT(largest_keyframe_step, 1e-4);
    if (!interpolate) {
      EXPECT_EQ(largest_step, largest_keyframe_step);
    }
    largest_step_in[interpolate] = largest_step;
  }
  // Both runs refine the keyframes alike; spread over kKeyframeEvery = 3 frame steps, no change
  // of correction from frame to frame exceeds a third of the largest jump at a keyframe.
  EXPECT_LE(largest_step_in[1], largest_step_in[0] / kKeyframeEvery * (1 + 1e-9));
}

// A sink set late receives at once the frames that are already final.
TEST(PipelineHistory, ALateSinkReceivesWhatIsAlreadyFinal) {
  PipelineParams p;
  p.method = PipelineMethod::kIcpFtf;
  PipelineBackEnd back_end(p);
  const Frame keyframe;
  for (int i = 0; i < 3; ++i) {
    PipelineFrame f;
    f.index = i;
    back_end.add(f, i == 0 ? &keyframe : nullptr);
  }
  int seen = 0;
  back_end.set_frame_sink([&](const PipelineFrame& f, const StampedPose&, const FrameVerdicts&) {
    EXPECT_EQ(f.index, seen++);
  });
  EXPECT_EQ(seen, 3);
}

// pipeline.filtered_depth: the refiners receive each keyframe's depth after the front end's
// bilateral filter, bit for bit, and the raw depth without it.
TEST(PipelineHistory, FilteredDepthGivesTheRefinersTheFrontEndsBilateralFilter) {
  Frame keyframe;
  keyframe.camera.width = 40;
  keyframe.camera.height = 30;
  keyframe.depth = DepthImage(40, 30);
  for (int v = 0; v < 30; ++v)
    for (int u = 0; u < 40; ++u)  // a slope with a deterministic ±1 cm ripple and a hole
      keyframe.depth(u, v) =
          (u == 7 && v == 9) ? 0.0f : 1.5f + 0.01f * u + 0.01f * ((u * 7 + v * 3) % 3 - 1);
  for (const bool filtered : {false, true}) {
    PipelineParams p;
    p.method = PipelineMethod::kJointFtf;
    p.filtered_depth = filtered;
    p.frontend.preprocess.bilateral_sigma_depth = 0.03f;
    std::vector<DepthImage> seen;
    const RefinerFactory recording = [&seen](const std::string& name, const JointParams& j,
                                             const IcpBundleParams& b) {
      return std::make_unique<RecordingRefiner>(shifting(name, j, b), &seen);
    };
    PipelineBackEnd back_end(p, CurvatureSink{}, recording);
    for (int i = 0; i < 2; ++i) {
      PipelineFrame f;
      f.index = i;
      back_end.add(f, &keyframe);
    }
    const DepthImage expected =
        filtered ? bilateral_filter(keyframe.depth, p.frontend.preprocess) : keyframe.depth;
    ASSERT_EQ(seen.size(), 2u);
    for (const DepthImage& d : seen) {
      ASSERT_EQ(d.width(), 40);
      EXPECT_TRUE(std::equal(d.data(), d.data() + 40 * 30, expected.data()));
    }
    // The filter changed the depth (else the test would not tell the two apart).
    EXPECT_FALSE(std::equal(expected.data(), expected.data() + 40 * 30, keyframe.depth.data()) &&
                 filtered);
  }
}

// A refiner that throws (out of memory, a lost GPU) is a failed refinement that says why: the
// keyframe keeps the front end's motion, and the next pair is refined as usual.
TEST(PipelineHistory, ARefinerThatThrowsIsAFailedRefinementAndTheRunGoesOn) {
  PipelineParams p;
  p.method = PipelineMethod::kJointFtf;
  PipelineBackEnd back_end(p, CurvatureSink{}, failing({1}, {}, FailingRefiner::How::kThrow));
  const Frame keyframe;
  for (int k = 0; k < 4; ++k)
    back_end.add(walk_frame(k), &keyframe);
  back_end.finish();
  const PipelineKeyframe& failed = back_end.keyframe(2);
  ASSERT_TRUE(failed.pair.has_value());
  EXPECT_EQ(failed.pair->verdict, RefinementVerdict::kError);
  EXPECT_EQ(failed.pair->method, "j-ftf");
  EXPECT_EQ(failed.pair->device, "");  // where it failed is not known
  EXPECT_NE(failed.pair->error.find("device lost"), std::string::npos) << failed.pair->error;
  EXPECT_TRUE(failed.used_front_end);
  EXPECT_FALSE(back_end.verdicts(2).trusted());
  EXPECT_LT(correction(back_end, 2).norm(), 1e-12);
  for (std::size_t k : {1, 3}) {  // the stand-in j-ftf moves x by 1 mm
    EXPECT_EQ(back_end.keyframe(k).pair->verdict, RefinementVerdict::kConverged) << k;
    EXPECT_FALSE(back_end.keyframe(k).used_front_end) << k;
    EXPECT_NEAR(correction(back_end, k).x(), 1e-3, 1e-12) << k;
  }
}

// A library caller's refiner that says "converged" of poses the pipeline cannot use (one too
// few: read past the end; one not finite) or throws what is no std::exception, and one out of
// memory, is a failed refinement that says why, as one that throws: the keyframe keeps the front
// end's motion.
TEST(PipelineHistory, ARefinerWhosePosesCannotBeUsedIsAFailedRefinement) {
  using How = FailingRefiner::How;
  for (const auto& [how, why] :
       {std::pair{How::kTooFewPoses, "the refiner gave 1 poses for 2 frames"},
        std::pair{How::kNanPose, "the refiner's pose 1 is no rigid motion"},
        std::pair{How::kTooManyPoseVerdicts, "the refiner gave 2 pose verdicts for 1 poses"},
        std::pair{How::kThrowOther, "an exception that is no std::exception"},
        // std::bad_alloc's what() says only that; the error says what ran out and on what.
        std::pair{How::kOutOfMemory,
                  "out of memory: j-ftf of 2 frames of 0x0 needs more memory"}}) {
    PipelineParams p;
    p.method = PipelineMethod::kJointFtf;
    PipelineBackEnd back_end(p, CurvatureSink{}, failing({1}, {}, how));
    const Frame keyframe;
    for (int k = 0; k < 4; ++k)
      back_end.add(walk_frame(k), &keyframe);
    back_end.finish();
    const PipelineKeyframe& failed = back_end.keyframe(2);
    ASSERT_TRUE(failed.pair.has_value()) << why;
    EXPECT_EQ(failed.pair->verdict, RefinementVerdict::kError) << why;
    EXPECT_NE(failed.pair->error.find(why), std::string::npos) << failed.pair->error;
    EXPECT_TRUE(failed.used_front_end) << why;
    EXPECT_FALSE(back_end.verdicts(2).trusted()) << why;
    EXPECT_LT(correction(back_end, 2).norm(), 1e-12) << why;
    EXPECT_NEAR(correction(back_end, 3).x(), 1e-3, 1e-12) << why;  // the next pair as usual
    for (std::size_t i = 0; i < 4; ++i)
      EXPECT_TRUE(back_end.refined_pose(i).pose.matrix().allFinite()) << why << ", frame " << i;
  }
}

// Q-full's poses are independent problems, each with its own verdict: a window whose first or
// last pose failed (too_few_quadrics) still moves its other keyframes, and only the failed one
// keeps the front end's motion from the previous keyframe and is not trusted. Six keyframes in
// windows of 3: [0 1 2] refines, [2 3 4] fails its first or last pose, and the window finish()
// refines, [4 5], fails its one pose.
TEST(PipelineHistory, AQFullPoseThatFailsFailsAlone) {
  using How = FailingRefiner::How;
  const Eigen::Vector3d offset(0.0, 2e-3, -1e-3);  // the stand-in window refiner's, per position
  for (const How how : {How::kFirstPoseFails, How::kLastPoseFails}) {
    const bool first = how == How::kFirstPoseFails;
    PipelineParams p;
    p.method = PipelineMethod::kFixedQuadrics;
    p.window = 3;
    PipelineBackEnd back_end(p, CurvatureSink{}, failing({}, {1, 2}, how));
    const Frame keyframe;
    for (int k = 0; k < 6; ++k)
      back_end.add(walk_frame(k), &keyframe);
    back_end.finish();
    // The correction of each keyframe's motion from the previous one: position j in its window
    // moves by j offsets from the window's first keyframe, a failed one by none from the previous.
    const Eigen::Vector3d none = Eigen::Vector3d::Zero(), twice = 2.0 * offset;
    const std::vector<Eigen::Vector3d> expected = {
        none, offset, offset, first ? none : offset, first ? twice : none, none};
    const std::size_t bad = first ? 3 : 4, good = first ? 4 : 3;
    for (std::size_t k = 1; k < 6; ++k) {
      const std::string at =
          std::string(first ? "first" : "last") + ", keyframe " + std::to_string(k);
      EXPECT_LT((correction(back_end, k) - expected[k]).norm(), 1e-12) << at;
      const bool failed = k == bad || k == 5;
      EXPECT_EQ(back_end.keyframe(k).used_front_end, failed) << at;
      EXPECT_EQ(back_end.verdicts(k).window,
                failed ? RefinementVerdict::kTooFewQuadrics : RefinementVerdict::kConverged)
          << at;
      EXPECT_EQ(back_end.verdicts(k).trusted(), !failed) << at;
    }
    EXPECT_EQ(back_end.keyframe(4).window->verdict, RefinementVerdict::kTooFewQuadrics);
    EXPECT_EQ(back_end.keyframe(4).window->pose_verdicts.size(), 2u);
    EXPECT_FALSE(back_end.keyframe(good).used_front_end);
  }
}

// A refiner's per-pose verdicts that name a usable pose it did not give are a failed refinement,
// not a read past its poses.
TEST(PipelineHistory, PoseVerdictsBeyondThePosesAreAFailedRefinement) {
  PipelineParams p;
  p.method = PipelineMethod::kFixedQuadrics;
  p.window = 3;
  PipelineBackEnd back_end(p, CurvatureSink{},
                           failing({}, {0}, FailingRefiner::How::kPoseVerdictsBeyondThePoses));
  const Frame keyframe;
  for (int k = 0; k < 3; ++k)
    back_end.add(walk_frame(k), &keyframe);
  back_end.finish();
  const PipelineKeyframe& last = back_end.keyframe(2);
  ASSERT_TRUE(last.window.has_value());
  EXPECT_EQ(last.window->verdict, RefinementVerdict::kError);
  EXPECT_NE(last.window->error.find("the refiner gave 2 poses for 3 frames"), std::string::npos)
      << last.window->error;
  for (std::size_t k = 1; k < 3; ++k)
    EXPECT_LT(correction(back_end, k).norm(), 1e-12) << k;
}

// A front-end pose that is no rigid motion (NaN) is refused before anything changes: each
// keyframe's pose builds on the previous one's, so one NaN spoiled every later keyframe.
TEST(PipelineHistory, AFrontEndPoseThatIsNoRigidMotionIsRefused) {
  PipelineParams p;
  p.method = PipelineMethod::kPipeline;
  p.window = 3;
  PipelineBackEnd back_end(p, CurvatureSink{}, shifting);
  const Frame keyframe;
  back_end.add(walk_frame(0), &keyframe);
  back_end.add(walk_frame(1), &keyframe);
  PipelineFrame bad = walk_frame(2);
  bad.front_end.pose.translation().x() = std::nan("");
  const std::string error = test::input_error_of([&] { back_end.add(bad, &keyframe); });
  EXPECT_NE(error.find("frame 2: the front end's pose is no rigid motion"), std::string::npos)
      << error;
  bad = walk_frame(2);
  bad.front_end.pose.linear() *= 1.01;  // not orthonormal
  EXPECT_THROW(back_end.add(bad, nullptr), InputError);
  EXPECT_EQ(back_end.frame_count(), 2u);
  EXPECT_EQ(back_end.keyframe_count(), 2u);
  back_end.add(walk_frame(2), &keyframe);  // completes the window of 3
  back_end.finish();
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_TRUE(back_end.keyframe(k).refined.pose.matrix().allFinite()) << k;
  EXPECT_EQ(back_end.keyframe(2).window->verdict, RefinementVerdict::kConverged);
}

// A keyframe from another camera (the split back end takes keyframes over DDS) is refused before
// the back end changes: the same frame from the right camera is then taken as usual.
TEST(PipelineHistory, AKeyframeFromAnotherCameraIsRefusedAndTheBackEndStaysAsItWas) {
  PipelineParams p;
  p.method = PipelineMethod::kJointFull;
  p.window = 3;
  PipelineBackEnd back_end(p, CurvatureSink{}, shifting);
  Frame keyframe;
  keyframe.camera = CameraIntrinsics{}.resized(64, 48);
  Frame other = keyframe;
  other.camera = keyframe.camera.resized(32, 24);
  back_end.add(walk_frame(0), &keyframe);
  back_end.add(walk_frame(1), &keyframe);
  const std::string error = test::input_error_of([&] { back_end.add(walk_frame(2), &other); });
  EXPECT_NE(error.find("keyframe of frame 2"), std::string::npos) << error;
  EXPECT_NE(error.find("32x24"), std::string::npos) << error;
  EXPECT_EQ(back_end.frame_count(), 2u);
  EXPECT_EQ(back_end.keyframe_count(), 2u);
  back_end.add(walk_frame(2), &keyframe);  // completes the window of 3
  ASSERT_TRUE(back_end.keyframe(2).window.has_value());
  EXPECT_EQ(back_end.keyframe(2).window->verdict, RefinementVerdict::kConverged);
  EXPECT_NEAR(correction(back_end, 2).y(), 2e-3, 1e-12);  // the stand-in window: y + 2 mm · j
}

// A sink that throws (a full disk, a lost publisher) reaches the caller once the frame is added:
// the back end stays whole and the next frame is accepted. add() after finish() is a logic error.
TEST(PipelineHistory, ASinkThatThrowsReachesTheCallerAndTheBackEndGoesOn) {
  PipelineParams p;
  p.method = PipelineMethod::kJointFtf;
  std::vector<int> maps;
  PipelineBackEnd back_end(
      p,
      [&](int keyframe, const Frame&, const QuadricMap&) {
        maps.push_back(keyframe);
        if (keyframe == 1) throw std::runtime_error("disk full");
      },
      shifting);
  std::vector<int> frames;
  back_end.set_frame_sink([&](const PipelineFrame& f, const StampedPose&, const FrameVerdicts&) {
    frames.push_back(f.index);
    if (f.index == 0) throw std::runtime_error("publisher gone");
  });
  Frame keyframe;
  keyframe.camera = CameraIntrinsics{}.resized(64, 48);
  keyframe.depth = DepthImage(64, 48, 2.0f);  // a wall: Quad IT gives the maps
  back_end.add(walk_frame(0), &keyframe);
  // Keyframe 1 completes the pair: keyframe 0's map and frame 0 go to the sinks; frame 0's throws.
  try {
    back_end.add(walk_frame(1), &keyframe);
    ADD_FAILURE() << "the sink's exception did not reach the caller";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "publisher gone");
  }
  EXPECT_EQ(back_end.frame_count(), 2u);
  EXPECT_EQ(back_end.keyframe_count(), 2u);
  // Keyframe 2: keyframe 1's map throws; frame 1 still reaches the frame sink.
  EXPECT_THROW(back_end.add(walk_frame(2), &keyframe), std::runtime_error);
  EXPECT_EQ(back_end.frame_count(), 3u);
  back_end.add(walk_frame(3), &keyframe);
  back_end.finish();
  EXPECT_EQ(maps, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(frames, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(back_end.keyframe(3).pair->verdict, RefinementVerdict::kConverged);
  EXPECT_THROW(back_end.add(walk_frame(4), &keyframe), std::logic_error);
}

// used_front_end says whether the keyframe's pose is the front end's motion from the previous
// keyframe, i.e. no refinement that covers it succeeded.
TEST(PipelineHistory, UsedFrontEndSaysWhetherNoRefinementMovedTheKeyframe) {
  const Frame keyframe;
  PipelineParams p;
  p.window = 3;
  {  // pipeline: J-ftf of keyframe 1 fails, its window succeeds and moves it
    p.method = PipelineMethod::kPipeline;
    PipelineBackEnd b(p, CurvatureSink{}, failing({0}, {}, FailingRefiner::How::kVerdict));
    for (int k = 0; k < 3; ++k)
      b.add(walk_frame(k), &keyframe);
    EXPECT_EQ(b.keyframe(1).pair->verdict, RefinementVerdict::kDiverged);
    EXPECT_FALSE(b.keyframe(1).used_front_end);
    EXPECT_GT(correction(b, 1).norm(), 1e-3);
  }
  {  // pipeline: the window fails, keyframe 2 keeps its J-ftf pose
    PipelineBackEnd b(p, CurvatureSink{}, failing({}, {0}, FailingRefiner::How::kVerdict));
    for (int k = 0; k < 3; ++k)
      b.add(walk_frame(k), &keyframe);
    EXPECT_EQ(b.keyframe(2).window->verdict, RefinementVerdict::kDiverged);
    EXPECT_FALSE(b.keyframe(2).used_front_end);
    EXPECT_NEAR(correction(b, 2).x(), 1e-3, 1e-12);
  }
  {  // ICP-ftf alone: nothing refines, every keyframe after the gauge is the front end's motion
    p.method = PipelineMethod::kIcpFtf;
    PipelineBackEnd b(p, CurvatureSink{}, shifting);
    for (int k = 0; k < 3; ++k)
      b.add(walk_frame(k), &keyframe);
    b.finish();
    EXPECT_FALSE(b.keyframe(0).used_front_end);
    EXPECT_TRUE(b.keyframe(1).used_front_end);
    EXPECT_TRUE(b.keyframe(2).used_front_end);
  }
  {  // J-full alone: a failed window leaves every keyframe after its gauge on the front end
    p.method = PipelineMethod::kJointFull;
    PipelineBackEnd b(p, CurvatureSink{}, failing({}, {0}, FailingRefiner::How::kVerdict));
    for (int k = 0; k < 3; ++k)
      b.add(walk_frame(k), &keyframe);
    EXPECT_FALSE(b.keyframe(0).used_front_end);
    for (std::size_t k : {1, 2}) {
      EXPECT_TRUE(b.keyframe(k).used_front_end) << k;
      EXPECT_LT(correction(b, k).norm(), 1e-12) << k;
    }
  }
}

}  // namespace
}  // namespace jpcr
