// Shared by the hostile-scene tests (issue 11): a short 160x120 synthetic walk through the whole
// pipeline, with a frame spoiled or a jump injected in memory, and checks on the per-frame
// verdicts (FrameVerdicts).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/io/synthetic_sequence.hpp"

namespace jpcr::hostile {

constexpr int kWidth = 160, kHeight = 120;

// The defaults (the front end's min_inliers scales itself with the image area), windows of 3,
// and every frame a keyframe (its overlap is below 0.999), so that the back end refines each.
inline PipelineParams small_frame_params() {
  PipelineParams p;
  p.method = PipelineMethod::kPipeline;
  p.window = 3;
  p.frontend.threads = 2;
  p.frontend.tracker.keyframe_overlap = 0.999;
  return p;
}

inline SyntheticSequence walk(const std::string& scene, int frames, double jump_at = -1) {
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
inline PipelineRun run(const SyntheticSequence& seq,
                       const std::function<void(std::size_t, Frame&)>& spoil = {},
                       const PipelineParams& params = small_frame_params()) {
  KeyframePipeline pipeline(params);
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

inline std::string describe(const FrameVerdicts& v) {
  std::string s = to_string(v.front_end);
  s += std::string(" pair ") + (v.pair ? to_string(*v.pair) : "-");
  s += std::string(" window ") + (v.window ? to_string(*v.window) : "-");
  return s;
}

inline void expect_trusted_before(const PipelineRun& r, std::size_t event) {
  for (std::size_t i = 0; i < event; ++i)
    EXPECT_TRUE(r.verdicts[i].trusted()) << "frame " << i << ": " << describe(r.verdicts[i]);
}

inline void expect_flagged(const PipelineRun& r, std::size_t i) {
  EXPECT_FALSE(r.verdicts.at(i).trusted()) << "frame " << i << ": " << describe(r.verdicts[i]);
}

// Tracking recovered: the last frame's alignment is ok again.
inline void expect_recovered(const PipelineRun& r) {
  EXPECT_EQ(r.verdicts.back().front_end, IcpVerdict::ok) << describe(r.verdicts.back());
}

// Keeps every 11th pixel in u and v: 1/121 < 1 % of the depth.
inline void keep_under_one_percent(Frame& f) {
  for (int v = 0; v < f.depth.height(); ++v)
    for (int u = 0; u < f.depth.width(); ++u)
      if (u % 11 != 0 || v % 11 != 0) f.depth(u, v) = 0.0f;
}

inline void fill_non_finite(Frame& f) {
  const float values[3] = {std::numeric_limits<float>::quiet_NaN(),
                           std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity()};
  for (int v = 0; v < f.depth.height(); ++v)
    for (int u = 0; u < f.depth.width(); ++u)
      f.depth(u, v) = values[(u + v) % 3];
}

}  // namespace jpcr::hostile
