#include "jpcr/io/dds/ros_messages.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// The generated structs use char* for strings; the serializer only reads them.
char* borrow(const std::string& text) {
  return const_cast<char*>(text.c_str());
}

template <typename Sequence, typename T>
Sequence borrow_sequence(const std::vector<T>& values) {
  Sequence s{};
  s._maximum = static_cast<std::uint32_t>(values.size());
  s._length = s._maximum;
  s._buffer = const_cast<T*>(values.data());
  s._release = false;
  return s;
}

constexpr double kUnknownCovariance = -1.0;  // REP 103/ROS: -1 on the diagonal means unknown

}  // namespace

std_msgs_msg_dds__Header_ header_message(double stamp, const std::string& frame_id) {
  std_msgs_msg_dds__Header_ h{};
  const RosStamp s = to_ros_stamp(stamp);
  h.stamp.sec = s.sec;
  h.stamp.nanosec = s.nanosec;
  h.frame_id = borrow(frame_id);
  return h;
}

geometry_msgs_msg_dds__Pose_ pose_message(const Eigen::Isometry3d& pose) {
  geometry_msgs_msg_dds__Pose_ p{};
  const Eigen::Vector3d t = pose.translation();
  const Eigen::Quaterniond q(pose.rotation());
  p.position = {t.x(), t.y(), t.z()};
  p.orientation = {q.x(), q.y(), q.z(), q.w()};
  return p;
}

void covariance_message(const Matrix6d& covariance, double out[36]) {
  Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> row_major(out);
  row_major = covariance;
}

RosPoseStamped pose_stamped_message(const StampedPose& pose, const std::string& frame_id) {
  RosPoseStamped m{};
  m.header = header_message(pose.timestamp, frame_id);
  m.pose = pose_message(pose.pose);
  return m;
}

RosOdometry odometry_message(const StampedPose& pose, const Matrix6d& covariance,
                             const std::string& world_frame_id,
                             const std::string& camera_frame_id) {
  RosOdometry m{};
  m.header = header_message(pose.timestamp, world_frame_id);
  m.child_frame_id = borrow(camera_frame_id);
  m.pose.pose = pose_message(pose.pose);
  covariance_message(covariance, m.pose.covariance);
  covariance_message(Matrix6d::Identity() * kUnknownCovariance, m.twist.covariance);
  return m;
}

RosImage image_message(const RosImageBuffer& image, double stamp, const std::string& frame_id) {
  RosImage m{};
  m.header = header_message(stamp, frame_id);
  m.height = image.height;
  m.width = image.width;
  m.encoding = borrow(image.encoding);
  m.is_bigendian = 0;
  m.step = image.step;
  m.data = borrow_sequence<dds_sequence_uint8>(image.data);
  return m;
}

RosCameraInfoMsg camera_info_message(const RosCameraInfo& info, double stamp,
                                     const std::string& frame_id) {
  RosCameraInfoMsg m{};
  m.header = header_message(stamp, frame_id);
  m.height = info.height;
  m.width = info.width;
  m.distortion_model = borrow(info.distortion_model);
  m.d = borrow_sequence<dds_sequence_double>(info.d);
  std::copy(info.k.begin(), info.k.end(), m.k);
  std::copy(info.r.begin(), info.r.end(), m.r);
  std::copy(info.p.begin(), info.p.end(), m.p);
  m.binning_x = info.binning_x;
  m.binning_y = info.binning_y;
  return m;
}

PathMessage::PathMessage(const Trajectory& trajectory, const std::string& frame_id)
    : frame_id_(frame_id) {
  poses_.reserve(trajectory.size());
  for (const StampedPose& p : trajectory)
    poses_.push_back(pose_stamped_message(p, frame_id_));
  const double stamp = trajectory.empty() ? 0.0 : trajectory.back().timestamp;
  message_.header = header_message(stamp, frame_id_);
  message_.poses = borrow_sequence<dds_sequence_geometry_msgs_msg_dds__PoseStamped_>(poses_);
}

KeyframeMessage::KeyframeMessage(const Frame& frame, const StampedPose& pose,
                                 const Matrix6d& covariance, DepthEncoding encoding,
                                 const std::string& world_frame_id,
                                 const std::string& camera_frame_id, int frame_index,
                                 const Trajectory& tracked)
    : world_frame_id_(world_frame_id),
      camera_frame_id_(camera_frame_id),
      depth_(encode_depth_image(frame.depth, encoding)),
      camera_(encode_camera_info(frame.camera)) {
  message_.header = header_message(frame.timestamp, world_frame_id_);
  message_.camera_info = camera_info_message(camera_, frame.timestamp, camera_frame_id_);
  message_.depth = image_message(depth_, frame.timestamp, camera_frame_id_);
  message_.pose.pose = pose_message(pose.pose);
  covariance_message(covariance, message_.pose.covariance);
  set_tracked(frame_index, tracked);
}

KeyframeMessage::KeyframeMessage(int frames, const Trajectory& tracked,
                                 const std::string& world_frame_id)
    : world_frame_id_(world_frame_id) {
  const double stamp = tracked.empty() ? 0.0 : tracked.back().timestamp;
  message_.header = header_message(stamp, world_frame_id_);
  // Empty, not null, strings: the serializer reads them.
  message_.camera_info.header = header_message(stamp, camera_frame_id_);
  message_.camera_info.distortion_model = borrow(camera_frame_id_);
  message_.depth.header = header_message(stamp, camera_frame_id_);
  message_.depth.encoding = borrow(camera_frame_id_);
  message_.pose.pose = pose_message(Eigen::Isometry3d::Identity());
  set_tracked(frames, tracked);
  message_.end_of_stream = true;
}

void KeyframeMessage::set_tracked(int frame_index, const Trajectory& tracked) {
  if (frame_index < static_cast<int>(tracked.size()))
    throw std::invalid_argument("KeyframeMessage: more tracked frames than frame_index");
  message_.frame_index = static_cast<std::uint32_t>(frame_index);
  tracked_.reserve(tracked.size());
  for (const StampedPose& p : tracked)
    tracked_.push_back(pose_stamped_message(p, world_frame_id_));
  message_.tracked = borrow_sequence<dds_sequence_geometry_msgs_msg_dds__PoseStamped_>(tracked_);
}

RosStamp stamp_of(const std_msgs_msg_dds__Header_& header) {
  return RosStamp{header.stamp.sec, header.stamp.nanosec};
}

Eigen::Isometry3d pose_of(const geometry_msgs_msg_dds__Pose_& pose) {
  Eigen::Quaterniond q(pose.orientation.w, pose.orientation.x, pose.orientation.y,
                       pose.orientation.z);
  const double norm = q.norm();
  if (!std::isfinite(norm) || norm == 0.0) throw InputError("pose orientation is not a rotation");
  const Eigen::Vector3d t(pose.position.x, pose.position.y, pose.position.z);
  if (!t.allFinite()) throw InputError("pose position is not finite");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

Matrix6d covariance_of(const double covariance[36]) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(covariance);
}

StampedPose stamped_pose_of(const RosPoseStamped& message) {
  return StampedPose{to_seconds(stamp_of(message.header)), pose_of(message.pose)};
}

Trajectory trajectory_of(const RosPath& message) {
  Trajectory t;
  t.reserve(message.poses._length);
  for (std::uint32_t i = 0; i < message.poses._length; ++i)
    t.push_back(stamped_pose_of(message.poses._buffer[i]));
  return t;
}

RosImageView image_view_of(const RosImage& message) {
  RosImageView v;
  v.height = message.height;
  v.width = message.width;
  v.encoding = message.encoding ? std::string_view(message.encoding) : std::string_view();
  v.is_bigendian = message.is_bigendian;
  v.step = message.step;
  v.data = message.data._buffer;
  v.size = message.data._length;
  return v;
}

RosCameraInfo camera_info_of(const RosCameraInfoMsg& message) {
  RosCameraInfo info;
  info.height = message.height;
  info.width = message.width;
  info.distortion_model = message.distortion_model ? message.distortion_model : "";
  info.d.assign(message.d._buffer, message.d._buffer + message.d._length);
  std::copy(message.k, message.k + 9, info.k.begin());
  std::copy(message.r, message.r + 9, info.r.begin());
  std::copy(message.p, message.p + 12, info.p.begin());
  info.binning_x = message.binning_x;
  info.binning_y = message.binning_y;
  return info;
}

namespace {

// The front end's ICP covariance as a keyframe carries it: finite, symmetric, with a
// non-negative diagonal (it is republished on odom as received).
void check_keyframe_covariance(const Matrix6d& c) {
  if (!c.allFinite()) throw InputError("keyframe covariance is not finite");
  const double scale = c.cwiseAbs().maxCoeff();
  if ((c - c.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale)
    throw InputError("keyframe covariance is not symmetric");
  if ((c.diagonal().array() < 0.0).any())
    throw InputError("keyframe covariance has a negative variance");
}

}  // namespace

DecodedKeyframe decode_keyframe(const RosKeyframe& message, const RosImageLimits& limits) {
  DecodedKeyframe k;
  if (message.frame_index > static_cast<std::uint32_t>(std::numeric_limits<int>::max()))
    throw InputError("keyframe frame_index " + std::to_string(message.frame_index) +
                     " is out of range");
  k.frame_index = static_cast<int>(message.frame_index);
  if (message.tracked._length > message.frame_index)
    throw InputError("keyframe " + std::to_string(message.frame_index) + " carries " +
                     std::to_string(message.tracked._length) + " tracked frames before it");
  for (std::uint32_t i = 0; i < message.tracked._length; ++i)
    k.tracked.push_back(stamped_pose_of(message.tracked._buffer[i]));
  k.end_of_stream = message.end_of_stream;
  if (k.end_of_stream) return k;
  const CameraIntrinsics camera = decode_camera_info(camera_info_of(message.camera_info), limits);
  k.frame = decode_depth_frame(image_view_of(message.depth), stamp_of(message.depth.header), camera,
                               limits);
  k.pose = StampedPose{k.frame.timestamp, pose_of(message.pose.pose)};
  if (message.depth.header.frame_id != nullptr) k.camera_frame_id = message.depth.header.frame_id;
  k.covariance = covariance_of(message.pose.covariance);
  check_keyframe_covariance(k.covariance);
  return k;
}

}  // namespace jpcr
