// Publishes jpcr's results as ROS 2 topics under DdsConfig::topic_prefix (default rt/jpcr/):
//
//   topic            type                      QoS (all reliable, transient local)
//   odom             nav_msgs/Odometry         keep last history_depth
//   keyframe_pose    geometry_msgs/PoseStamped keep last history_depth
//   path             nav_msgs/Path             keep last 1
//                                              (keep last history_depth: PathUpdates::kIncremental)
//   curvature        sensor_msgs/Image 32FC2   keep last image_history_depth
//   curvature_color  sensor_msgs/Image rgb8    keep last image_history_depth
//   curvature_sd     sensor_msgs/Image 32FC1   keep last image_history_depth
//
// Transient local: each writer keeps its last samples (the depth above) while it lives, and a
// reader that asks for transient-local durability gets them on matching, so it loses nothing
// written before discovery completed; a volatile reader (ROS 2's default) matches as well and
// gets only what comes after. The images cost image_history_depth maps of memory per topic.
//
// Poses are T_wc (camera to world) with header.frame_id = world_frame_id; images and odom's child
// frame carry the camera frame: camera_frame_id until set_camera_frame_id names the received
// depth's. Thread-compatible: one thread per publisher.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <ostream>
#include <string>

#include <Eigen/Core>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"
#include "jpcr/io/log_budget.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/image.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

enum class ResultTopic {
  kOdometry,
  kKeyframePose,
  kPath,
  kCurvature,
  kCurvatureColor,
  kCurvatureSd
};

/// What a path holds: the whole refined trajectory (each path supersedes the one before, so the
/// path topic keeps the last one), or the frames made final since the previous path and those
/// still held (a pipeline with keep_history = false): then every path carries poses no other
/// does, and the topic keeps history_depth of them for readers that must take each one.
enum class PathUpdates { kWhole, kIncremental };

/// "odom", "keyframe_pose", "path", "curvature", "curvature_color", "curvature_sd".
const char* to_string(ResultTopic topic);
/// PREFIX + name.
std::string result_topic_name(const DdsConfig& config, ResultTopic topic);
/// The QoS of the table above; readers that want every sample use the same (transient local).
DdsQos result_topic_qos(const DdsConfig& config, ResultTopic topic,
                        PathUpdates paths = PathUpdates::kWhole);

class DdsResultPublisher {
 public:
  /// Creates the six writers; throws DdsError when Cyclone refuses. A sample Cyclone refuses
  /// later (larger than its MaxSampleSize, out of resources) is not published: it is counted
  /// (writes_failed) and logged to `log` (default std::cerr; the first 10 lines, then one per
  /// 10 s), and publishing goes on: one lost result does not stop the run that makes them.
  /// `paths` sets the path topic's history (result_topic_qos).
  DdsResultPublisher(const DdsParticipant& participant, const DdsConfig& config,
                     std::ostream* log = nullptr, PathUpdates paths = PathUpdates::kWhole);
  ~DdsResultPublisher();
  DdsResultPublisher(const DdsResultPublisher&) = delete;
  DdsResultPublisher& operator=(const DdsResultPublisher&) = delete;

  /// The front end's pose of a frame with its 6x6 covariance over (x, y, z, rx, ry, rz).
  void publish_odometry(const StampedPose& pose, const Matrix6d& covariance);
  /// A refined keyframe: its pose, its κ1/κ2 map (1/m, NaN invalid) and, each when not empty,
  /// the map's colour rendering and its sd map (1/m, NaN where none; quadric/curvature_spread.hpp);
  /// all stamped with pose.timestamp. Throws std::invalid_argument when `sd` is not empty and
  /// differs from `curvature` in size.
  void publish_keyframe(const StampedPose& pose, const Image<Eigen::Vector2f>& curvature,
                        const ColorImage& color, const Image<float>& sd = {});
  /// The refined trajectory (all keyframes); late subscribers receive the last one.
  void publish_path(const Trajectory& trajectory);

  /// The camera frame of what follows (odom's child frame, the images' frame_id): the received
  /// depth's header.frame_id, so that results sit in the camera's own tf frame. An empty `id`
  /// keeps the current one (DdsConfig::camera_frame_id at first).
  void set_camera_frame_id(const std::string& id);

  /// Waits until reliable readers acknowledged every sample of every topic (before exiting).
  bool flush(std::chrono::milliseconds timeout) const;

  /// Readers matched on `topic` (for logs and for waiting in tests).
  int matched(ResultTopic topic) const;
  /// Reader endpoints matched, summed over the six topics (a process reading two topics counts
  /// twice).
  int matched_readers() const;
  /// Waits until matched_readers() >= count, `timeout` in all, so that a producer faster than
  /// discovery (jpcr_run --dds) writes its first sample once its readers are there; a writer
  /// that is gone keeps no history. False on timeout, or as soon as keep_waiting (when given)
  /// says no. These are this writer's matches: a volatile reader that has not yet matched the
  /// writer in turn (discovery runs both ways, on loopback within milliseconds) can still miss
  /// what is written before it has; a transient-local reader gets it (the last `depth` samples).
  bool wait_for_readers(int count, std::chrono::milliseconds timeout,
                        const std::function<bool()>& keep_waiting = {}) const;
  /// Samples Cyclone refused to publish, over all topics.
  std::size_t writes_failed() const { return writes_failed_; }

 private:
  struct Writers;
  template <typename Writer, typename Msg>
  void write(const Writer& writer, const Msg& sample);

  DdsConfig config_;
  std::ostream* log_;
  std::unique_ptr<Writers> writers_;
  std::size_t writes_failed_ = 0;
  LogBudget failure_lines_;
};

}  // namespace jpcr
