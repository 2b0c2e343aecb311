// Degenerate and hostile input through the whole pipeline (issue 11): a single plane, a
// featureless corridor, a frame with < 1 % valid depth, a 50 cm jump between two frames and a
// frame full of NaN/Inf. Each must give a verdict that is not ok on the affected frames
// (FrameVerdicts: the front end's IcpVerdict and the back end's RefinementVerdicts), the frames
// before it must stay trusted (so the flag is the event's, not the scene's), the pipeline keeps
// going to the last frame with finite poses, and tracking recovers where it can.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <optional>

#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/io/synthetic_sequence.hpp"

namespace jpcr {
namespace {

constexpr int kWidth = 160, kHeight = 120;

// The front end's default min_inliers is set for 640x480 frames (a 160x120 coarsest level);
// at 160x120 the coarsest level has 1/16 of the pixels, so the same fraction is 1/16 of it.
PipelineParams small_frame_params() {
  PipelineParams p;
  p.method = PipelineMethod::kPipeline;
  p.window = 3;
  p.frontend.threads = 2;
  p.frontend.icp.min_inliers = p.frontend.icp.min_inliers * (kWidth * kHeight) / (640 * 480);
  return p;
}

SyntheticSequence walk(const std::string& scene, int frames, double jump_at = -1) {
  SyntheticSequenceOptions o;
  o.scene = scene;
  o.frames = frames;
  o.width = kWidth;
  o.height = kHeight;
  o.seed = 11;
  SyntheticSequence seq = make_synthetic_sequence(o);
  if (jump_at < 0) return seq;
  // A sudden 50 cm jump: from frame jump_at on the camera is 0.5 m to the side (world x).
  Trajectory t = seq.trajectory();
  for (std::size_t i = static_cast<std::size_t>(jump_at); i < t.size(); ++i)
    t[i].pose.pretranslate(Eigen::Vector3d(0.5, 0.0, 0.0));
  return SyntheticSequence(seq.scene(), seq.camera(), t, seq.noise(), seq.seed());
}

struct PipelineRun {
  std::vector<FrameVerdicts> verdicts;
  Trajectory trajectory;
};

// Runs the pipeline over every frame; `spoil` may change frame i before it goes in.
PipelineRun run(const SyntheticSequence& seq, const std::function<void(std::size_t, Frame&)>& spoil = {}) {
  KeyframePipeline pipeline(small_frame_params());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    Frame f = seq.load(i);
    if (spoil) spoil(i, f);
    pipeline.add(f);
  }
  pipeline.finish();
  PipelineRun r;
  for (std::size_t i = 0; i < seq.size(); ++i)
    r.verdicts.push_back(pipeline.verdicts(i));
  r.trajectory = pipeline.trajectory();
  EXPECT_EQ(r.trajectory.size(), seq.size());
  for (const StampedPose& p : r.trajectory)
    EXPECT_TRUE(p.pose.matrix().allFinite()) << "frame at " << p.timestamp;
  return r;
}

std::string describe(const FrameVerdicts& v) {
  std::string s = to_string(v.front_end);
  s += std::string(" pair ") + (v.pair ? to_string(*v.pair) : "-");
  s += std::string(" window ") + (v.window ? to_string(*v.window) : "-");
  return s;
}

void expect_trusted_before(const PipelineRun& r, std::size_t event) {
  for (std::size_t i = 0; i < event; ++i)
    EXPECT_TRUE(r.verdicts[i].trusted()) << "frame " << i << ": " << describe(r.verdicts[i]);
}

void expect_flagged(const PipelineRun& r, std::size_t i) {
  EXPECT_FALSE(r.verdicts.at(i).trusted()) << "frame " << i << ": " << describe(r.verdicts[i]);
}

// Tracking recovered: the last frame's alignment is ok again.
void expect_recovered(const PipelineRun& r) {
  EXPECT_EQ(r.verdicts.back().front_end, IcpVerdict::ok) << describe(r.verdicts.back());
}

// Keeps every 11th pixel in u and v: 1/121 < 1 % of the depth.
void keep_under_one_percent(Frame& f) {
  for (int v = 0; v < f.depth.height(); ++v)
    for (int u = 0; u < f.depth.width(); ++u)
      if (u % 11 != 0 || v % 11 != 0) f.depth(u, v) = 0.0f;
}

void fill_non_finite(Frame& f) {
  const float values[3] = {std::numeric_limits<float>::quiet_NaN(),
                           std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity()};
  for (int v = 0; v < f.depth.height(); ++v)
    for (int u = 0; u < f.depth.width(); ++u)
      f.depth(u, v) = values[(u + v) % 3];
}

// The control: the same walk through room_spheres with nothing spoiled is trusted throughout,
// so the flags below come from the events.
TEST(HostileScenes, AnUnspoiledWalkIsTrustedThroughout) {
  const PipelineRun r = run(walk("room_spheres", 8));
  expect_trusted_before(r, r.verdicts.size());
}

TEST(HostileScenes, SinglePlaneIsNotOk) {
  const PipelineRun r = run(walk("single_plane", 6));
  for (std::size_t i = 1; i < r.verdicts.size(); ++i) {
    expect_flagged(r, i);
    EXPECT_EQ(r.verdicts[i].front_end, IcpVerdict::degenerate) << i;
  }
}

// The front end finds the corridor degenerate, or fails outright once its last motion no longer
// fits; where a keyframe makes the back end run, J-ftf and J-full must not settle on it either
// (they did, at max_iterations, 40 cm off per frame, before RefinementVerdict::kDegenerate).
TEST(HostileScenes, FeaturelessCorridorIsNotOk) {
  const PipelineRun r = run(walk("corridor", 6));
  int refined = 0;
  for (std::size_t i = 1; i < r.verdicts.size(); ++i) {
    const FrameVerdicts& v = r.verdicts[i];
    expect_flagged(r, i);
    EXPECT_NE(v.front_end, IcpVerdict::ok) << i;
    for (const std::optional<RefinementVerdict>& b : {v.pair, v.window})
      if (b) {
        ++refined;
        EXPECT_EQ(*b, RefinementVerdict::kDegenerate) << "frame " << i << ": " << describe(v);
      }
  }
  EXPECT_GT(refined, 0) << "the back end never ran on the corridor";
}

TEST(HostileScenes, FrameWithUnderOnePercentValidDepthIsNotOk) {
  const std::size_t bad = 4;
  const PipelineRun r = run(walk("room_spheres", 8), [&](std::size_t i, Frame& f) {
    if (i == bad) keep_under_one_percent(f);
  });
  expect_trusted_before(r, bad);
  expect_flagged(r, bad);
  EXPECT_EQ(r.verdicts[bad].front_end, IcpVerdict::too_few_points);
  expect_recovered(r);
}

TEST(HostileScenes, FiftyCentimetreJumpIsNotOk) {
  const std::size_t jump = 4;
  const PipelineRun r = run(walk("room_spheres", 8, jump));
  expect_trusted_before(r, jump);
  expect_flagged(r, jump);
  expect_recovered(r);
}

TEST(HostileScenes, DepthFullOfNanAndInfIsNotOk) {
  const std::size_t bad = 4;
  const PipelineRun r = run(walk("room_spheres", 8), [&](std::size_t i, Frame& f) {
    if (i == bad) fill_non_finite(f);
  });
  expect_trusted_before(r, bad);
  expect_flagged(r, bad);
  EXPECT_EQ(r.verdicts[bad].front_end, IcpVerdict::too_few_points);
  expect_recovered(r);
}

}  // namespace
}  // namespace jpcr
