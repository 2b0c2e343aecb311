// The ROS 2 messages of io/dds/idl as idlc's C structs, and conversions between them and jpcr
// types. Messages built for sending borrow their strings and buffers from the caller (zero copy):
// keep the arguments alive until the message is written. Received messages are converted at once
// into owned jpcr values.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "geometry_msgs.h"
#include "jpcr/io/dds/dds_endpoint.hpp"
#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/se3.hpp"
#include "jpcr_msgs.h"
#include "nav_msgs.h"
#include "sensor_msgs.h"

namespace jpcr {

using RosPoseStamped = geometry_msgs_msg_dds__PoseStamped_;
using RosOdometry = nav_msgs_msg_dds__Odometry_;
using RosPath = nav_msgs_msg_dds__Path_;
using RosImage = sensor_msgs_msg_dds__Image_;
using RosCameraInfoMsg = sensor_msgs_msg_dds__CameraInfo_;
using RosKeyframe = jpcr_msgs_msg_dds__Keyframe_;

#define JPCR_DDS_TYPE(Msg, desc)                                       \
  template <>                                                          \
  struct DdsType<Msg> {                                                \
    static const dds_topic_descriptor_t& descriptor() { return desc; } \
  }
JPCR_DDS_TYPE(RosPoseStamped, geometry_msgs_msg_dds__PoseStamped__desc);
JPCR_DDS_TYPE(RosOdometry, nav_msgs_msg_dds__Odometry__desc);
JPCR_DDS_TYPE(RosPath, nav_msgs_msg_dds__Path__desc);
JPCR_DDS_TYPE(RosImage, sensor_msgs_msg_dds__Image__desc);
JPCR_DDS_TYPE(RosCameraInfoMsg, sensor_msgs_msg_dds__CameraInfo__desc);
JPCR_DDS_TYPE(RosKeyframe, jpcr_msgs_msg_dds__Keyframe__desc);
#undef JPCR_DDS_TYPE

// ---- jpcr → message (borrowing) ------------------------------------------------------------

std_msgs_msg_dds__Header_ header_message(double stamp, const std::string& frame_id);
geometry_msgs_msg_dds__Pose_ pose_message(const Eigen::Isometry3d& pose);
/// Row-major 6x6 over (x, y, z, rot x, rot y, rot z): jpcr's (v, ω) order is ROS's order.
void covariance_message(const Matrix6d& covariance, double out[36]);

RosPoseStamped pose_stamped_message(const StampedPose& pose, const std::string& frame_id);
/// Odometry of T_wc: header.frame_id = world, child_frame_id = camera; zero twist with a
/// covariance of -1 on the diagonal ("unknown", the ROS convention).
RosOdometry odometry_message(const StampedPose& pose, const Matrix6d& covariance,
                             const std::string& world_frame_id, const std::string& camera_frame_id);
RosImage image_message(const RosImageBuffer& image, double stamp, const std::string& frame_id);
RosCameraInfoMsg camera_info_message(const RosCameraInfo& info, double stamp,
                                     const std::string& frame_id);

/// A Path with its own storage for the poses (not copyable: the message points into it).
class PathMessage {
 public:
  PathMessage(const Trajectory& trajectory, const std::string& frame_id);
  PathMessage(const PathMessage&) = delete;
  PathMessage& operator=(const PathMessage&) = delete;
  const RosPath& message() const { return message_; }

 private:
  std::string frame_id_;
  std::vector<RosPoseStamped> poses_;
  RosPath message_{};
};

/// A Keyframe with its own storage (depth in `encoding`, camera info, pose and covariance), its
/// frame index and the front end's poses of the frames tracked since the previous keyframe.
class KeyframeMessage {
 public:
  KeyframeMessage(const Frame& frame, const StampedPose& pose, const Matrix6d& covariance,
                  DepthEncoding encoding, const std::string& world_frame_id,
                  const std::string& camera_frame_id, int frame_index = 0,
                  const Trajectory& tracked = {});
  /// The end-of-stream marker: no keyframe; `tracked` are the frames after the last keyframe and
  /// `frames` the number of frames tracked in all.
  KeyframeMessage(int frames, const Trajectory& tracked, const std::string& world_frame_id);
  KeyframeMessage(const KeyframeMessage&) = delete;
  KeyframeMessage& operator=(const KeyframeMessage&) = delete;
  const RosKeyframe& message() const { return message_; }

 private:
  void set_tracked(int frame_index, const Trajectory& tracked);

  std::string world_frame_id_, camera_frame_id_;
  RosImageBuffer depth_;
  RosCameraInfo camera_;
  std::vector<RosPoseStamped> tracked_;
  RosKeyframe message_{};
};

// ---- message → jpcr (copying) --------------------------------------------------------------

RosStamp stamp_of(const std_msgs_msg_dds__Header_& header);
/// The pose; the quaternion is normalised (throws InputError when it is zero or not finite).
Eigen::Isometry3d pose_of(const geometry_msgs_msg_dds__Pose_& pose);
Matrix6d covariance_of(const double covariance[36]);
StampedPose stamped_pose_of(const RosPoseStamped& message);
Trajectory trajectory_of(const RosPath& message);
/// Borrows the fields of a received image (valid while the sample is).
RosImageView image_view_of(const RosImage& message);
RosCameraInfo camera_info_of(const RosCameraInfoMsg& message);

/// A received keyframe, decoded and checked like a depth frame (frame, pose and covariance are
/// empty in the end-of-stream marker).
struct DecodedKeyframe {
  Frame frame;
  StampedPose pose;
  Matrix6d covariance = Matrix6d::Zero();
  int frame_index = 0;
  Trajectory tracked;  // the frames frame_index - tracked.size() ... frame_index - 1
  bool end_of_stream = false;
  std::string camera_frame_id;  // the depth's header.frame_id
};
DecodedKeyframe decode_keyframe(const RosKeyframe& message, const RosImageLimits& limits);

}  // namespace jpcr
