// Publishes what a KeyframePipeline produces on the jpcr result topics (DdsResultPublisher), for
// jpcr_node and jpcr_run --dds:
//   odom             after every frame: the frame's current refined pose (trajectory().back())
//                    with the front end's ICP covariance (PipelineFrame::icp_covariance; zero
//                    for the first frame, the gauge)
//   keyframe_pose,   when a keyframe's curvature map is final (the pipeline's CurvatureSink):
//   curvature,       its refined pose, κ1/κ2 map (32FC2) and render_curvature (rgb8)
//   curvature_color
//   path             the whole refined trajectory (every frame) after each frame that added a
//                    keyframe (and so refined), and after finish()
#pragma once

#include <chrono>
#include <cstddef>

#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/io/dds/dds_result_publisher.hpp"

namespace jpcr::cli {

class PipelinePublisher {
 public:
  PipelinePublisher(const DdsParticipant& participant, const DdsConfig& config)
      : publisher_(participant, config) {}

  /// The CurvatureSink body; `pipeline` is the one calling it.
  void keyframe_final(const KeyframePipeline& pipeline, int keyframe, const QuadricMap& quadrics);
  /// After each KeyframePipeline::add().
  void frame_added(const KeyframePipeline& pipeline, const PipelineFrame& frame);
  /// After KeyframePipeline::finish(): the final path.
  void finished(const KeyframePipeline& pipeline);

  bool flush(std::chrono::milliseconds timeout) const { return publisher_.flush(timeout); }
  std::size_t keyframes_published() const { return keyframes_published_; }

 private:
  DdsResultPublisher publisher_;
  std::size_t keyframes_seen_ = 0;
  std::size_t keyframes_published_ = 0;
};

}  // namespace jpcr::cli
