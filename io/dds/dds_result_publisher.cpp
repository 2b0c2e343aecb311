#include "jpcr/io/dds/dds_result_publisher.hpp"

#include <iostream>
#include <stdexcept>
#include <string>

#include "jpcr/io/dds/dds_endpoint.hpp"
#include "jpcr/io/dds/ros_messages.hpp"

namespace jpcr {

struct DdsResultPublisher::Writers {
  Writers(const DdsParticipant& p, const DdsConfig& c, PathUpdates paths)
      : odometry(p, result_topic_name(c, ResultTopic::kOdometry),
                 result_topic_qos(c, ResultTopic::kOdometry)),
        keyframe_pose(p, result_topic_name(c, ResultTopic::kKeyframePose),
                      result_topic_qos(c, ResultTopic::kKeyframePose)),
        path(p, result_topic_name(c, ResultTopic::kPath),
             result_topic_qos(c, ResultTopic::kPath, paths)),
        curvature(p, result_topic_name(c, ResultTopic::kCurvature),
                  result_topic_qos(c, ResultTopic::kCurvature)),
        curvature_color(p, result_topic_name(c, ResultTopic::kCurvatureColor),
                        result_topic_qos(c, ResultTopic::kCurvatureColor)),
        curvature_sd(p, result_topic_name(c, ResultTopic::kCurvatureSd),
                     result_topic_qos(c, ResultTopic::kCurvatureSd)) {}

  DdsWriter<RosOdometry> odometry;
  DdsWriter<RosPoseStamped> keyframe_pose;
  DdsWriter<RosPath> path;
  DdsWriter<RosImage> curvature;
  DdsWriter<RosImage> curvature_color;
  DdsWriter<RosImage> curvature_sd;
};

const char* to_string(ResultTopic topic) {
  switch (topic) {
    case ResultTopic::kOdometry:
      return "odom";
    case ResultTopic::kKeyframePose:
      return "keyframe_pose";
    case ResultTopic::kPath:
      return "path";
    case ResultTopic::kCurvature:
      return "curvature";
    case ResultTopic::kCurvatureColor:
      return "curvature_color";
    case ResultTopic::kCurvatureSd:
      return "curvature_sd";
  }
  return "?";
}

std::string result_topic_name(const DdsConfig& config, ResultTopic topic) {
  return config.topic_prefix + to_string(topic);
}

DdsQos result_topic_qos(const DdsConfig& config, ResultTopic topic, PathUpdates paths) {
  // Every topic is transient local: the writer keeps its last `depth` samples for a reader that
  // asks for them, so such a reader loses nothing to discovery; a volatile reader matches too.
  switch (topic) {
    case ResultTopic::kPath:
      return DdsQos{true, true, paths == PathUpdates::kWhole ? 1 : config.history_depth};
    case ResultTopic::kCurvature:
    case ResultTopic::kCurvatureColor:
    case ResultTopic::kCurvatureSd:
      return DdsQos{true, true, config.image_history_depth};
    default:
      return DdsQos{true, true, config.history_depth};
  }
}

DdsResultPublisher::DdsResultPublisher(const DdsParticipant& participant, const DdsConfig& config,
                                       std::ostream* log, PathUpdates paths)
    : config_(config),
      log_(log ? log : &std::cerr),
      writers_(std::make_unique<Writers>(participant, config, paths)) {}

DdsResultPublisher::~DdsResultPublisher() = default;

template <typename Writer, typename Msg>
void DdsResultPublisher::write(const Writer& writer, const Msg& sample) {
  try {
    writer.write(sample);
  } catch (const DdsError& e) {
    ++writes_failed_;
    std::size_t left_out = 0;
    if (failure_lines_.allow(left_out))
      *log_ << "jpcr dds: not published (" << writes_failed_ << " in all): " << e.what()
            << LogBudget::note(left_out) << std::endl;
  }
}

void DdsResultPublisher::publish_odometry(const StampedPose& pose, const Matrix6d& covariance) {
  write(writers_->odometry,
        odometry_message(pose, covariance, config_.world_frame_id, config_.camera_frame_id));
}

void DdsResultPublisher::publish_keyframe(const StampedPose& pose,
                                          const Image<Eigen::Vector2f>& curvature,
                                          const ColorImage& color, const Image<float>& sd) {
  if (!sd.empty() && (sd.width() != curvature.width() || sd.height() != curvature.height()))
    throw std::invalid_argument("DdsResultPublisher::publish_keyframe: the sd map is " +
                                std::to_string(sd.width()) + "x" + std::to_string(sd.height()) +
                                ", the curvature map " + std::to_string(curvature.width()) + "x" +
                                std::to_string(curvature.height()));
  write(writers_->keyframe_pose, pose_stamped_message(pose, config_.world_frame_id));
  if (!curvature.empty()) {
    const RosImageBuffer k = encode_curvature_image(curvature);
    write(writers_->curvature, image_message(k, pose.timestamp, config_.camera_frame_id));
  }
  if (!color.empty()) {
    const RosImageBuffer c = encode_rgb8_image(color);
    write(writers_->curvature_color, image_message(c, pose.timestamp, config_.camera_frame_id));
  }
  if (!sd.empty()) {
    const RosImageBuffer s = encode_curvature_sd_image(sd);
    write(writers_->curvature_sd, image_message(s, pose.timestamp, config_.camera_frame_id));
  }
}

void DdsResultPublisher::publish_path(const Trajectory& trajectory) {
  const PathMessage path(trajectory, config_.world_frame_id);
  write(writers_->path, path.message());
}

void DdsResultPublisher::set_camera_frame_id(const std::string& id) {
  if (!id.empty()) config_.camera_frame_id = id;
}

bool DdsResultPublisher::flush(std::chrono::milliseconds timeout) const {
  const Writers& w = *writers_;
  return w.odometry.wait_for_acks(timeout) && w.keyframe_pose.wait_for_acks(timeout) &&
         w.path.wait_for_acks(timeout) && w.curvature.wait_for_acks(timeout) &&
         w.curvature_color.wait_for_acks(timeout) && w.curvature_sd.wait_for_acks(timeout);
}

int DdsResultPublisher::matched(ResultTopic topic) const {
  switch (topic) {
    case ResultTopic::kOdometry:
      return writers_->odometry.matched();
    case ResultTopic::kKeyframePose:
      return writers_->keyframe_pose.matched();
    case ResultTopic::kPath:
      return writers_->path.matched();
    case ResultTopic::kCurvature:
      return writers_->curvature.matched();
    case ResultTopic::kCurvatureColor:
      return writers_->curvature_color.matched();
    case ResultTopic::kCurvatureSd:
      return writers_->curvature_sd.matched();
  }
  return 0;
}

int DdsResultPublisher::matched_readers() const {
  int sum = 0;
  for (const ResultTopic topic :
       {ResultTopic::kOdometry, ResultTopic::kKeyframePose, ResultTopic::kPath,
        ResultTopic::kCurvature, ResultTopic::kCurvatureColor, ResultTopic::kCurvatureSd})
    sum += matched(topic);
  return sum;
}

bool DdsResultPublisher::wait_for_readers(int count, std::chrono::milliseconds timeout,
                                          const std::function<bool()>& keep_waiting) const {
  return poll_until([&] { return matched_readers() >= count; },
                    std::chrono::steady_clock::now() + timeout, keep_waiting);
}

}  // namespace jpcr
