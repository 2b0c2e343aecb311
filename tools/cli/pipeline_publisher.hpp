// Publishes what a PipelineBackEnd (a KeyframePipeline, or the back-end process of the split
// deployment) produces on the jpcr result topics (DdsResultPublisher), for jpcr_node and
// jpcr_run --dds:
//   odom             after every frame: the frame's current refined pose (trajectory().back())
//                    with the front end's pose covariance accumulated along its alignments
//                    (PipelineFrame::pose_covariance in ROS's x, y, z, rx, ry, rz order; zero
//                    for the gauge, 1 m / 1 rad per axis before it); not in the split deployment,
//                    where the front-end process publishes its own poses
//   keyframe_pose,   when a keyframe's curvature map is final (the pipeline's CurvatureSink):
//   curvature,       its refined pose, κ1/κ2 map (32FC2), render_curvature (rgb8) and, unless
//   curvature_color, dds.curvature_sd is false, the map's sd (32FC1, curvature_spread on the
//   curvature_sd     keyframe's vertices with the pattern and fit the map was made with)
//   path             the whole refined trajectory (every frame) after each frame that added a
//                    keyframe (and so refined), and after finish(). With keep_history = false
//                    the pipeline forgets each frame once its pose is final: a path then holds
//                    the frames made final since the previous path (each final pose is
//                    published once) followed by the frames still held, and the path topic
//                    keeps history_depth paths: a reader must take every one (with its
//                    depth, result_topic_qos(..., PathUpdates::kIncremental)).
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <utility>

#include "jpcr/backend/pipeline_back_end.hpp"
#include "jpcr/io/dds/dds_result_publisher.hpp"
#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr::cli {

class PipelinePublisher {
 public:
  /// `keep_history` is the pipeline's (PipelineParams): false makes the paths incremental
  /// (PathUpdates::kIncremental), kept history_depth deep on the path topic. With `spread` (the
  /// quadric parameters the maps are made with, PipelineParams::joint.quadric), keyframe_final
  /// computes each map's sd where its caller has none. config.curvature_sd = false: no sd.
  PipelinePublisher(const DdsParticipant& participant, const DdsConfig& config, bool keep_history,
                    std::optional<QuadricParams> spread = std::nullopt)
      : path_updates_(keep_history ? PathUpdates::kWhole : PathUpdates::kIncremental),
        publisher_(participant, config, nullptr, path_updates_),
        publish_sd_(config.curvature_sd),
        spread_(std::move(spread)) {}

  /// Before the first frame: with keep_history = false, takes the frames `pipeline` makes final
  /// (its FrameSink) for the next path. `pipeline` keeps history as the constructor was told.
  void attach(PipelineBackEnd& pipeline);

  /// The CurvatureSink body; `pipeline` is the one calling it, `frame` the keyframe `quadrics`
  /// were fitted on. Publishes `sd` when it is not empty (a map the caller computed already, as
  /// jpcr_run's CurvatureWriter does), else the map's curvature_spread when constructed with
  /// `spread`, else no sd; none with dds.curvature_sd false.
  void keyframe_final(const PipelineBackEnd& pipeline, int keyframe, const Frame& frame,
                      const QuadricMap& quadrics, const Image<float>& sd = {});
  /// After each KeyframePipeline::add(): odom, and the path when the frame added a keyframe.
  void frame_added(const PipelineBackEnd& pipeline, const PipelineFrame& frame);
  /// The path, when keyframes were added since the last one published.
  void path_if_refined(const PipelineBackEnd& pipeline);
  /// After PipelineBackEnd::finish(): the final path.
  void finished(const PipelineBackEnd& pipeline);

  /// DdsResultPublisher::set_camera_frame_id.
  void set_camera_frame_id(const std::string& id) { publisher_.set_camera_frame_id(id); }
  bool flush(std::chrono::milliseconds timeout) const { return publisher_.flush(timeout); }
  /// DdsResultPublisher::wait_for_readers.
  bool wait_for_readers(int count, std::chrono::milliseconds timeout,
                        const std::function<bool()>& keep_waiting = {}) const {
    return publisher_.wait_for_readers(count, timeout, keep_waiting);
  }
  int matched_readers() const { return publisher_.matched_readers(); }
  std::size_t keyframes_published() const { return keyframes_published_; }
  /// Samples Cyclone refused to publish (DdsResultPublisher::writes_failed).
  std::size_t writes_failed() const { return publisher_.writes_failed(); }

 private:
  void publish_path(const PipelineBackEnd& pipeline);

  PathUpdates path_updates_;
  DdsResultPublisher publisher_;
  bool publish_sd_;
  std::optional<QuadricParams> spread_;
  Trajectory final_since_path_;   // keep_history = false: final frames not yet in a path
  std::size_t final_frames_ = 0;  // ... and frames [0, final_frames_) have gone to the sink
  std::size_t keyframes_seen_ = 0;
  std::size_t keyframes_published_ = 0;
};

}  // namespace jpcr::cli
