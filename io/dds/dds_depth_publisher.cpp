#include "jpcr/io/dds/dds_depth_publisher.hpp"

#include "jpcr/io/dds/ros_messages.hpp"

namespace jpcr {

struct DdsDepthPublisher::Writers {
  Writers(const DdsParticipant& p, const DdsConfig& c)
      : camera_info(p, c.camera_info_topic, c.camera_info_qos()),
        depth(p, c.depth_topic, c.depth_qos()) {}
  DdsWriter<RosCameraInfoMsg> camera_info;
  DdsWriter<RosImage> depth;
};

DdsDepthPublisher::DdsDepthPublisher(const DdsParticipant& participant, const DdsConfig& config,
                                     DepthEncoding encoding)
    : config_(config),
      encoding_(encoding),
      writers_(std::make_unique<Writers>(participant, config)) {}

DdsDepthPublisher::~DdsDepthPublisher() = default;

bool DdsDepthPublisher::publish(const Frame& frame, const std::function<bool()>& keep_waiting) {
  const RosCameraInfo info = encode_camera_info(frame.camera);
  writers_->camera_info.write(camera_info_message(info, frame.timestamp, config_.camera_frame_id));
  const RosImageBuffer depth = encode_depth_image(frame.depth, encoding_);
  const auto message = image_message(depth, frame.timestamp, config_.camera_frame_id);
  if (!config_.input_keep_all) {
    writers_->depth.write(message);
    return true;
  }
  while (!writers_->depth.try_write(message))  // each try waits up to max_blocking_ms
    if (keep_waiting && !keep_waiting()) return false;
  return true;
}

int DdsDepthPublisher::matched() const {
  return writers_->depth.matched();
}

bool DdsDepthPublisher::flush(std::chrono::milliseconds timeout) const {
  return writers_->camera_info.wait_for_acks(timeout) && writers_->depth.wait_for_acks(timeout);
}

bool DdsDepthPublisher::wait_for_subscribers(int count, std::chrono::milliseconds timeout,
                                             const std::function<bool()>& keep_waiting) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;  // one for both topics
  return writers_->depth.wait_matched(count, deadline, keep_waiting) &&
         writers_->camera_info.wait_matched(count, deadline, keep_waiting);
}

}  // namespace jpcr
