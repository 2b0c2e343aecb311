#include "cli/pipeline_publisher.hpp"

#include <stdexcept>
#include <utility>

#include "jpcr/io/curvature_colors.hpp"
#include "jpcr/quadric/curvature_spread.hpp"

namespace jpcr::cli {

void PipelinePublisher::attach(PipelineBackEnd& pipeline) {
  if (pipeline.params().keep_history != (path_updates_ == PathUpdates::kWhole))
    throw std::logic_error("PipelinePublisher: the pipeline's keep_history differs from its own");
  if (pipeline.params().keep_history) return;  // trajectory() holds every frame
  pipeline.set_frame_sink(
      [this](const PipelineFrame& frame, const StampedPose& refined, const FrameVerdicts&) {
        final_since_path_.push_back(refined);
        final_frames_ = static_cast<std::size_t>(frame.index) + 1;
      });
}

void PipelinePublisher::publish_path(const PipelineBackEnd& pipeline) {
  Trajectory path = std::move(final_since_path_);
  final_since_path_.clear();
  // The pipeline may still hold frames it handed to the sink (it forgets them lazily, and never
  // the newest): those are in `path` already.
  const Trajectory held = pipeline.trajectory();
  const std::size_t first = pipeline.first_frame();
  for (std::size_t k = 0; k < held.size(); ++k)
    if (first + k >= final_frames_) path.push_back(held[k]);
  publisher_.publish_path(path);
}

void PipelinePublisher::keyframe_final(const PipelineBackEnd& pipeline, int keyframe,
                                       const Frame& frame, const QuadricMap& quadrics,
                                       const Image<float>& sd) {
  const StampedPose& pose = pipeline.keyframe(static_cast<std::size_t>(keyframe)).refined;
  Image<float> own_sd;
  // Computed only for a reader (about one Quad IT fit): a transient-local reader that matches
  // later gets only the maps kept from keyframes when a reader was there (README, DDS topics).
  if (publish_sd_ && sd.empty() && spread_ && !quadrics.curvature.empty() &&
      publisher_.matched(ResultTopic::kCurvatureSd) > 0) {
    own_sd = curvature_spread(quadrics, compute_vertex_map(frame.depth, frame.camera), *spread_);
  }
  const Image<float>& published = !publish_sd_ || sd.empty() ? own_sd : sd;
  publisher_.publish_keyframe(pose, quadrics.curvature, render_curvature(quadrics.curvature),
                              published);
  ++keyframes_published_;
}

void PipelinePublisher::frame_added(const PipelineBackEnd& pipeline, const PipelineFrame& frame) {
  // The frame's own pose only: copying the whole trajectory per frame grew with the run. Its
  // covariance is the front end's along its chain of alignments, in ROS's order.
  const StampedPose pose = pipeline.refined_pose(static_cast<std::size_t>(frame.index));
  publisher_.publish_odometry(
      pose, position_rotation_covariance(frame.pose_covariance, pose.pose.translation()));
  path_if_refined(pipeline);
}

void PipelinePublisher::path_if_refined(const PipelineBackEnd& pipeline) {
  if (pipeline.keyframe_count() == keyframes_seen_) return;
  keyframes_seen_ = pipeline.keyframe_count();
  publish_path(pipeline);
}

void PipelinePublisher::finished(const PipelineBackEnd& pipeline) {
  publish_path(pipeline);
}

}  // namespace jpcr::cli
