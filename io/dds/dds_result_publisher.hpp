// Publishes jpcr's results as ROS 2 topics under DdsConfig::topic_prefix (default rt/jpcr/):
//
//   topic            type                      QoS
//   odom             nav_msgs/Odometry         reliable, volatile, keep last history_depth
//   keyframe_pose    geometry_msgs/PoseStamped reliable, volatile, keep last history_depth
//   path             nav_msgs/Path             reliable, transient local, keep last 1
//   curvature        sensor_msgs/Image 32FC2   reliable, volatile, keep last image_history_depth
//   curvature_color  sensor_msgs/Image rgb8    reliable, volatile, keep last image_history_depth
//
// Poses are T_wc (camera to world) with header.frame_id = world_frame_id; images and odom's child
// frame carry the camera frame: camera_frame_id until set_camera_frame_id names the received
// depth's. Thread-compatible: one thread per publisher.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/image.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

enum class ResultTopic { kOdometry, kKeyframePose, kPath, kCurvature, kCurvatureColor };

/// "odom", "keyframe_pose", "path", "curvature", "curvature_color".
const char* to_string(ResultTopic topic);
/// PREFIX + name.
std::string result_topic_name(const DdsConfig& config, ResultTopic topic);
/// The QoS of the table above; readers that want every sample use the same.
DdsQos result_topic_qos(const DdsConfig& config, ResultTopic topic);

class DdsResultPublisher {
 public:
  /// Creates the five writers; throws DdsError when Cyclone refuses.
  DdsResultPublisher(const DdsParticipant& participant, const DdsConfig& config);
  ~DdsResultPublisher();
  DdsResultPublisher(const DdsResultPublisher&) = delete;
  DdsResultPublisher& operator=(const DdsResultPublisher&) = delete;

  /// The front end's pose of a frame with its 6x6 covariance over (x, y, z, rx, ry, rz).
  void publish_odometry(const StampedPose& pose, const Matrix6d& covariance);
  /// A refined keyframe: its pose, its κ1/κ2 map (1/m, NaN invalid) and, when not empty, the
  /// map's colour rendering; all stamped with pose.timestamp.
  void publish_keyframe(const StampedPose& pose, const Image<Eigen::Vector2f>& curvature,
                        const ColorImage& color);
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

 private:
  struct Writers;
  DdsConfig config_;
  std::unique_ptr<Writers> writers_;
};

}  // namespace jpcr
