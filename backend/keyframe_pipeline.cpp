#include "jpcr/backend/keyframe_pipeline.hpp"

#include <chrono>

namespace jpcr {

PipelineFrontEnd::PipelineFrontEnd(const PipelineParams& params)
    : method_(params.method), tracker_(params.frontend, params.initial_pose) {}

PipelineFrame PipelineFrontEnd::track(const Frame& frame, bool* keyframe) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0 = Clock::now();
  const TrackResult track = tracker_.track(frame);
  PipelineFrame f;
  f.index = track.index;
  f.front_end = track.T_wc;
  // The gauge was aligned to nothing and is exact by definition; a frame before it (no points
  // to align against yet) keeps the default alignment's verdict and unknown covariance.
  f.icp_verdict = track.is_gauge ? IcpVerdict::ok : track.icp.verdict;
  f.kept_last_motion = track.kept_last_motion;
  if (!track.is_gauge) f.icp_covariance = track.icp.covariance;
  f.pose_covariance = track.pose_covariance;
  f.track_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  // The single methods refine every consecutive frame from the gauge on; the pipeline follows
  // the front end. A frame before the gauge is no keyframe: it has no depth to refine.
  *keyframe =
      track.is_keyframe || (method_ != PipelineMethod::kPipeline && tracker_.has_keyframe());
  return f;
}

KeyframePipeline::KeyframePipeline(const PipelineParams& params, CurvatureSink sink,
                                   const RefinerFactory& refiners)
    : PipelineBackEnd(params, std::move(sink), refiners), front_end_(params) {}

const PipelineFrame& KeyframePipeline::add(const Frame& frame) {
  bool keyframe = false;
  const PipelineFrame f = front_end_.track(frame, &keyframe);
  return PipelineBackEnd::add(f, keyframe ? &frame : nullptr);
}

}  // namespace jpcr
