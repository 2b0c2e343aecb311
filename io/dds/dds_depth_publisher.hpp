// Publishes depth frames the way a ROS 2 depth camera driver does: sensor_msgs/CameraInfo on
// DdsConfig::camera_info_topic, then sensor_msgs/Image (16UC1 mm or 32FC1 m) on depth_topic, with
// the same stamp and camera_frame_id. Used by jpcr_dds_play and the tests.
#pragma once

#include <chrono>
#include <functional>
#include <memory>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"
#include "jpcr/io/dds/ros_image.hpp"
#include "jpcr/quadric/frame.hpp"

namespace jpcr {

class DdsDepthPublisher {
 public:
  DdsDepthPublisher(const DdsParticipant& participant, const DdsConfig& config,
                    DepthEncoding encoding);
  ~DdsDepthPublisher();
  DdsDepthPublisher(const DdsDepthPublisher&) = delete;
  DdsDepthPublisher& operator=(const DdsDepthPublisher&) = delete;

  /// Publishes the frame's camera_info and depth image. With DdsConfig::input_keep_all the depth
  /// writer is reliable KEEP_ALL: while a KEEP_ALL reader's queue (jpcr_node with the same
  /// setting) is full, this waits, asking keep_waiting (when given) between tries of
  /// DdsQos::max_blocking_ms, and returns false, the image unwritten, once it says no. Otherwise
  /// it never waits and returns true. Throws DdsError when Cyclone refuses a sample.
  bool publish(const Frame& frame, const std::function<bool()>& keep_waiting = {});
  /// Subscribers matched on the depth topic.
  int matched() const;
  /// Waits until reliable subscribers acknowledged every frame (call before exiting).
  bool flush(std::chrono::milliseconds timeout) const;
  /// Waits until `count` subscribers are matched on both the depth and the camera_info topic,
  /// `timeout` in all; false on timeout, or as soon as keep_waiting (when given) says no.
  bool wait_for_subscribers(int count, std::chrono::milliseconds timeout,
                            const std::function<bool()>& keep_waiting = {}) const;

 private:
  struct Writers;
  DdsConfig config_;
  DepthEncoding encoding_;
  std::unique_ptr<Writers> writers_;
};

}  // namespace jpcr
