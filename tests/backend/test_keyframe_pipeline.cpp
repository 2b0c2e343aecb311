// The pipeline that ties the front end to the back end: ICP-ftf alone reproduces the tracker,
// J-ftf chained over consecutive frames beats it on a noise-free synthetic walk, J-full windows
// refine and chain at their shared frames, the gauge stays, every keyframe gets a curvature map,
// and bad input is refused.
#include <gtest/gtest.h>

#include <cstdio>

#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/io/trajectory_metrics.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

SyntheticSequence walk(int frames) {
  SyntheticSequenceOptions o;
  o.scene = "room_spheres";
  o.frames = frames;
  o.width = 160;
  o.height = 120;
  o.seed = 4;
  return make_synthetic_sequence(o);
}

struct PipelineRun {
  Trajectory trajectory;
  std::vector<PipelineKeyframe> keyframes;
  std::vector<int> curvature_keyframes;
};

PipelineRun run_pipeline(const SyntheticSequence& seq, PipelineMethod method, int window = 3) {
  PipelineParams p;
  p.method = method;
  p.window = window;
  p.frontend.threads = 2;
  PipelineRun r;
  KeyframePipeline pipeline(p, [&](int k, const Frame&, const QuadricMap& q) {
    EXPECT_GT(q.valid_count(), q.status.size() / 2);
    r.curvature_keyframes.push_back(k);
  });
  for (std::size_t i = 0; i < seq.size(); ++i)
    pipeline.add(seq.load(i));
  pipeline.finish();
  r.trajectory = pipeline.trajectory();
  r.keyframes = pipeline.keyframes();
  return r;
}

// The pose of frame 0 is the gauge: identity, as the tracker starts it.
void expect_gauge(const PipelineRun& r) {
  EXPECT_TRUE(r.trajectory.front().pose.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
}

Trajectory relative_to_first(const Trajectory& t) {
  Trajectory out = t;
  for (StampedPose& p : out)
    p.pose = t.front().pose.inverse() * p.pose;
  return out;
}

TEST(KeyframePipeline, IcpFtfIsTheFrontEndAlone) {
  const SyntheticSequence seq = walk(4);
  const PipelineRun r = run_pipeline(seq, PipelineMethod::kIcpFtf);
  ASSERT_EQ(r.trajectory.size(), 4u);
  expect_gauge(r);
  EXPECT_TRUE(r.curvature_keyframes.empty());
  ASSERT_FALSE(r.keyframes.empty());  // the first frame at least
  for (const PipelineKeyframe& k : r.keyframes) {
    EXPECT_FALSE(k.pair.has_value());
    EXPECT_TRUE(k.refined.pose.isApprox(k.front_end.pose, 1e-12));
  }
}

// Each frame carries its ICP covariance for odometry consumers; the gauge frame has none.
TEST(KeyframePipeline, FramesCarryTheFrontEndsIcpCovariance) {
  const SyntheticSequence seq = walk(3);
  PipelineParams p;
  p.method = PipelineMethod::kIcpFtf;
  p.frontend.threads = 2;
  KeyframePipeline pipeline(p);
  for (std::size_t i = 0; i < seq.size(); ++i)
    pipeline.add(seq.load(i));
  ASSERT_EQ(pipeline.frames().size(), 3u);
  EXPECT_TRUE(pipeline.frames()[0].icp_covariance.isZero(0.0));
  for (std::size_t i = 1; i < 3; ++i) {
    const Matrix6d& c = pipeline.frames()[i].icp_covariance;
    EXPECT_TRUE(c.allFinite());
    EXPECT_TRUE((c.diagonal().array() > 0.0).all()) << c.diagonal().transpose();
    EXPECT_TRUE(c.isApprox(c.transpose(), 1e-9));
  }
}

// Another gauge moves the whole trajectory rigidly and changes nothing else: every method works
// on relative motions (invariance under a rigid motion of the world frame).
TEST(KeyframePipeline, AnInitialPoseMovesTheTrajectoryRigidly) {
  const SyntheticSequence seq = walk(3);
  Vector6d xi;
  xi << 1.5, -0.4, 0.9, 0.3, -1.2, 0.7;
  const Eigen::Isometry3d gauge = se3_exp(xi);
  for (PipelineMethod method : {PipelineMethod::kIcpFtf, PipelineMethod::kJointFtf}) {
    Trajectory t[2];
    for (int g = 0; g < 2; ++g) {
      PipelineParams p;
      p.method = method;
      p.frontend.threads = 2;
      if (g == 1) p.initial_pose = gauge;
      KeyframePipeline pipeline(p);
      for (std::size_t i = 0; i < seq.size(); ++i)
        pipeline.add(seq.load(i));
      pipeline.finish();
      t[g] = pipeline.trajectory();
    }
    ASSERT_EQ(t[1].size(), t[0].size());
    EXPECT_TRUE(t[1].front().pose.isApprox(gauge, 1e-12));
    for (std::size_t i = 0; i < t[0].size(); ++i) {
      const Eigen::Isometry3d moved = gauge * t[0][i].pose;
      EXPECT_LT((moved.matrix() - t[1][i].pose.matrix()).cwiseAbs().maxCoeff(), 1e-6)
          << to_string(method) << " frame " << i;
    }
  }
}

TEST(KeyframePipeline, JointFtfBeatsIcpFtfOnANoiseFreeWalk) {
  const SyntheticSequence seq = walk(4);
  const Trajectory gt = relative_to_first(seq.ground_truth_trajectory());
  const PipelineRun icp = run_pipeline(seq, PipelineMethod::kIcpFtf);
  const PipelineRun ftf = run_pipeline(seq, PipelineMethod::kJointFtf);
  expect_gauge(ftf);
  for (std::size_t k = 1; k < ftf.keyframes.size(); ++k) {
    ASSERT_TRUE(ftf.keyframes[k].pair.has_value());
    EXPECT_TRUE(ftf.keyframes[k].pair->converged()) << to_string(ftf.keyframes[k].pair->verdict);
  }
  const RelativeErrors e_icp = compute_relative_errors(gt, icp.trajectory);
  const RelativeErrors e_ftf = compute_relative_errors(gt, ftf.trajectory);
  std::printf("relative RMS: ICP-ftf %.3g m %.3g rad, J-ftf %.3g m %.3g rad\n",
              e_icp.translation_rms, e_icp.rotation_rms, e_ftf.translation_rms, e_ftf.rotation_rms);
  // Measured 2026-12-05: ICP-ftf 8.9e-4 m / 1.2e-3 rad, J-ftf 7.5e-5 m / 4.4e-5 rad (12x and
  // 28x lower); a quarter leaves a factor of 3 over the translation's.
  EXPECT_LT(e_ftf.translation_rms, 0.25 * e_icp.translation_rms);
  EXPECT_LT(e_ftf.rotation_rms, 0.25 * e_icp.rotation_rms);
  // Every keyframe has a curvature map, each exactly once, in order: J-ftf's for every keyframe
  // that starts a pair, Quad IT's for the last.
  EXPECT_EQ(ftf.curvature_keyframes, (std::vector<int>{0, 1, 2, 3}));
  for (std::size_t k = 0; k < 4; ++k)
    EXPECT_EQ(ftf.keyframes[k].curvature, k < 3 ? "j-ftf" : "quad-it") << "keyframe " << k;
}

TEST(KeyframePipeline, JointFullWindowsChainAtTheirSharedFrames) {
  const SyntheticSequence seq = walk(5);
  const Trajectory gt = relative_to_first(seq.ground_truth_trajectory());
  const PipelineRun icp = run_pipeline(seq, PipelineMethod::kIcpFtf);
  const PipelineRun full =
      run_pipeline(seq, PipelineMethod::kJointFull, 3);  // windows {0,1,2} and {2,3,4}
  expect_gauge(full);
  ASSERT_EQ(full.keyframes.size(), 5u);
  EXPECT_TRUE(full.keyframes[2].window.has_value());
  EXPECT_TRUE(full.keyframes[4].window.has_value());
  EXPECT_FALSE(full.keyframes[3].window.has_value());
  EXPECT_LT(compute_relative_errors(gt, full.trajectory).translation_rms,
            compute_relative_errors(gt, icp.trajectory).translation_rms);
  EXPECT_EQ(full.curvature_keyframes, (std::vector<int>{0, 1, 2, 3, 4}));
  // J-full's quadrics live on each window's first keyframe; the others keep Quad IT's.
  const std::vector<std::string> sources = {"j-full", "quad-it", "j-full", "quad-it", "quad-it"};
  for (std::size_t k = 0; k < 5; ++k)
    EXPECT_EQ(full.keyframes[k].curvature, sources[k]) << "keyframe " << k;
  // A keyframe's pose in the trajectory is its refined pose to the bit (keyframes.txt and
  // trajectory.txt agree).
  for (const PipelineKeyframe& k : full.keyframes)
    EXPECT_TRUE(full.trajectory[static_cast<std::size_t>(k.frame)].pose.matrix() ==
                k.refined.pose.matrix())
        << "keyframe of frame " << k.frame;
  // Q-full holds the quadrics fixed: every map is Quad IT's, and says so.
  const PipelineRun fixed = run_pipeline(seq, PipelineMethod::kFixedQuadrics, 3);
  ASSERT_TRUE(fixed.keyframes[2].window.has_value());
  EXPECT_TRUE(usable(fixed.keyframes[2].window->verdict));
  for (std::size_t k = 0; k < 5; ++k)
    EXPECT_EQ(fixed.keyframes[k].curvature, "quad-it") << "keyframe " << k;
}

TEST(KeyframePipeline, RefusesBadInput) {
  PipelineParams p;
  p.window = 1;
  EXPECT_THROW(KeyframePipeline{p}, InputError);
  PipelineParams scaled;
  scaled.initial_pose.linear() *= 2.0;  // the gauge must be a rigid motion
  EXPECT_THROW(KeyframePipeline{scaled}, InputError);
  EXPECT_THROW(parse_pipeline_method("bundle"), InputError);
  KeyframePipeline pipeline;
  const SyntheticSequence seq = walk(1);
  pipeline.add(seq.load(0));
  Frame small = seq.load(0);
  small.depth = DepthImage(80, 60, 1.0f);
  EXPECT_THROW(pipeline.add(small), InputError);
}

// The split deployment's back end gets the frames from another process: a lost or reordered one
// is refused rather than hung on the wrong keyframe.
TEST(PipelineBackEnd, RefusesFramesOutOfOrder) {
  PipelineParams p;
  p.method = PipelineMethod::kIcpFtf;
  PipelineBackEnd back_end(p);
  const SyntheticSequence seq = walk(1);
  const Frame frame = seq.load(0);
  PipelineFrame f;
  f.index = 1;
  EXPECT_THROW(back_end.add(f, &frame), InputError);  // frame 0 is missing
  f.index = 0;
  EXPECT_EQ(back_end.add(f, &frame).keyframe, 0);
  f.index = 1;
  EXPECT_EQ(back_end.add(f, nullptr).keyframe, 0);     // hangs on keyframe 0
  EXPECT_THROW(back_end.add(f, nullptr), InputError);  // frame 1 again
  f.index = 3;
  EXPECT_THROW(back_end.add(f, nullptr), InputError);  // frame 2 is missing
  EXPECT_EQ(back_end.frames().size(), 2u);
  EXPECT_EQ(back_end.keyframes().size(), 1u);
}

// Frames before the first keyframe (a sensor that starts blank) hang on no keyframe: each keeps
// its front-end pose and verdict, goes to the sink at once, and is forgotten like any other,
// also when no keyframe ever comes.
TEST(PipelineBackEnd, FramesBeforeTheFirstKeyframeKeepTheirFrontEndPoses) {
  const SyntheticSequence seq = walk(3);
  for (const bool keep_history : {true, false}) {
    PipelineParams p;
    p.method = PipelineMethod::kJointFtf;
    p.keep_history = keep_history;
    PipelineBackEnd back_end(p);
    std::vector<int> sunk;
    back_end.set_frame_sink(
        [&](const PipelineFrame& f, const StampedPose& pose, const FrameVerdicts& v) {
          sunk.push_back(f.index);
          if (f.keyframe >= 0) return;
          EXPECT_TRUE(pose.pose.isApprox(f.front_end.pose, 0.0)) << "frame " << f.index;
          EXPECT_EQ(v.front_end, IcpVerdict::too_few_points);
          EXPECT_FALSE(v.pair.has_value());
          EXPECT_FALSE(v.trusted());
        });
    for (int i = 0; i < 2; ++i) {
      PipelineFrame f;
      f.index = i;
      f.icp_verdict = IcpVerdict::too_few_points;
      f.front_end.pose.translation() = Eigen::Vector3d(0.1 * i, 0.0, 0.0);
      EXPECT_EQ(back_end.add(f, nullptr).keyframe, -1);
      EXPECT_EQ(sunk.size(), static_cast<std::size_t>(i + 1));  // final at once
    }
    EXPECT_EQ(back_end.keyframe_count(), 0u);
    const Frame frame = seq.load(0);
    PipelineFrame f;
    f.index = 2;
    EXPECT_EQ(back_end.add(f, &frame).keyframe, 0);
    f.index = 3;
    EXPECT_EQ(back_end.add(f, nullptr).keyframe, 0);
    back_end.finish();
    EXPECT_EQ(sunk, (std::vector<int>{0, 1, 2, 3}));
    if (keep_history) {
      EXPECT_DOUBLE_EQ(back_end.trajectory()[1].pose.translation().x(), 0.1);
      EXPECT_EQ(back_end.verdicts(2).front_end, IcpVerdict::ok);
    }
  }
  PipelineParams p;  // no keyframe at all: the front end's poses, as they came
  p.keep_history = false;
  PipelineBackEnd back_end(p);
  std::size_t sunk = 0;
  back_end.set_frame_sink(
      [&](const PipelineFrame&, const StampedPose&, const FrameVerdicts&) { ++sunk; });
  for (int i = 0; i < 50; ++i) {
    PipelineFrame f;
    f.index = i;
    back_end.add(f, nullptr);
  }
  back_end.finish();
  EXPECT_EQ(sunk, 50u);
  EXPECT_EQ(back_end.keyframe_count(), 0u);
  EXPECT_LT(back_end.frames().size(), 50u);  // forgotten as they went to the sink
}

// A sensor that starts blank: the first frame with points is the gauge, and the run from there
// is the run that starts there (the blank frames change no pose after them); the
// blank frames stay at the gauge's pose, untrusted. Keyframe 0 used to be the blank frame 0,
// and 7 of the 8 frames' J-ftf pairs and J-full windows failed against it.
TEST(KeyframePipeline, ABlankStartMovesTheGaugeToTheFirstFrameWithPoints) {
  const SyntheticSequence seq = walk(8);
  for (const PipelineMethod method : {PipelineMethod::kPipeline, PipelineMethod::kJointFtf}) {
    PipelineParams p;
    p.method = method;
    p.window = 3;
    p.frontend.threads = 2;
    KeyframePipeline blank_start(p), late_start(p);
    for (std::size_t i = 0; i < seq.size(); ++i) {
      Frame f = seq.load(i);
      if (i < 2) {
        f.depth = DepthImage(f.depth.width(), f.depth.height(), 0.0f);
      } else {
        late_start.add(f);
      }
      blank_start.add(f);
    }
    blank_start.finish();
    late_start.finish();
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(blank_start.frame(i).keyframe, -1);
      EXPECT_TRUE(blank_start.refined_pose(i).pose.isApprox(Eigen::Isometry3d::Identity(), 0.0));
      EXPECT_FALSE(blank_start.verdicts(i).trusted());
    }
    ASSERT_EQ(blank_start.keyframe_count(), late_start.keyframe_count());
    EXPECT_EQ(blank_start.keyframe(0).frame, 2);
    for (std::size_t i = 2; i < seq.size(); ++i) {
      const std::string at = std::string(to_string(method)) + ", frame " + std::to_string(i);
      // The front end's poses to the bit; the refiners' threaded sums add in any order.
      EXPECT_TRUE(
          blank_start.frame(i).front_end.pose.isApprox(late_start.frame(i - 2).front_end.pose, 0.0))
          << at;
      EXPECT_TRUE(
          blank_start.refined_pose(i).pose.isApprox(late_start.refined_pose(i - 2).pose, 1e-12))
          << at;
      EXPECT_EQ(blank_start.verdicts(i).trusted(), late_start.verdicts(i - 2).trusted()) << at;
      EXPECT_TRUE(blank_start.verdicts(i).trusted()) << at;
    }
  }
}

// An application's refiner factory (e.g. J-ftf on a GPU) is what the pipeline refines with: every
// refinement goes through the refiners it made, and with CPU refiners the result is the default.
class CountingRefiner : public Refiner {
 public:
  CountingRefiner(std::unique_ptr<Refiner> inner, int* calls)
      : inner_(std::move(inner)), calls_(calls) {}
  using Refiner::refine;
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override {
    ++*calls_;
    return inner_->refine(vertices, camera, initial_poses, initial_quadrics);
  }
  std::string name() const override { return inner_->name(); }
  const JointParams& params() const override { return inner_->params(); }
  bool refines_quadrics() const override { return inner_->refines_quadrics(); }

 private:
  std::unique_ptr<Refiner> inner_;
  int* calls_;
};

TEST(PipelineBackEnd, RefinesWithTheInjectedFactory) {
  std::vector<std::string> names;
  int calls = 0;
  const RefinerFactory factory = [&](const std::string& name, const JointParams& joint,
                                     const IcpBundleParams& bundle) -> std::unique_ptr<Refiner> {
    names.push_back(name);
    return std::make_unique<CountingRefiner>(make_refiner(name, joint, bundle), &calls);
  };
  PipelineParams p;
  p.method = PipelineMethod::kPipeline;
  p.window = 2;
  PipelineBackEnd pipeline(p, {}, factory);
  EXPECT_EQ(names, (std::vector<std::string>{"j-ftf", "j-full"}));

  names.clear();
  p.method = PipelineMethod::kJointFtf;  // every consecutive pair: 2 refinements of 3 frames
  p.frontend.threads = 2;
  const SyntheticSequence seq = walk(3);
  KeyframePipeline injected(p, {}, factory), plain(p);
  for (std::size_t i = 0; i < seq.size(); ++i) {
    injected.add(seq.load(i));
    plain.add(seq.load(i));
  }
  injected.finish();
  plain.finish();
  EXPECT_EQ(names, (std::vector<std::string>{"j-ftf"}));
  EXPECT_EQ(calls, 2);
  const Trajectory a = injected.trajectory(), b = plain.trajectory();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_TRUE(a[i].pose.isApprox(b[i].pose, 1e-12)) << "frame " << i;
  const RefinerFactory none = [](const std::string&, const JointParams&, const IcpBundleParams&) {
    return std::unique_ptr<Refiner>();
  };
  EXPECT_THROW(PipelineBackEnd(p, {}, none), std::invalid_argument);
}

}  // namespace
}  // namespace jpcr
