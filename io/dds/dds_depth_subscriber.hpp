// Receives depth frames from a ROS 2 depth camera: sensor_msgs/Image (16UC1 in mm or 32FC1 in m)
// on DdsConfig::depth_topic with the latest sensor_msgs/CameraInfo of camera_info_topic. Every
// sample is checked (io/dds/ros_image.hpp); a bad one is dropped with one line on the log naming
// the topic and the problem (a flood of them: the first 10 lines, then one per 10 s that says how
// many were left out), and reception goes on.
//
// Samples are taken from Cyclone as they arrive (a listener on Cyclone's receive thread) into a
// queue of at most image_history_depth images, the KEEP_LAST depth of the input QoS, and decoded
// frames wait for the caller under the same bound: when the caller is slower than the camera,
// the oldest waiting image is dropped, counted (frames_dropped()) and logged, never lost silently
// in the reader's history nor kept to pile up behind the caller. With DdsConfig::input_keep_all
// the reader is KEEP_ALL with a resource limit of image_history_depth images, and images are taken
// from it only as the caller makes room: nothing is dropped, and a reliable KEEP_ALL camera waits
// (Cyclone holds its writes back while the reader is full). Cyclone does so by retrying the full
// reader on its receive thread, so nothing else reaches the process meanwhile: a camera_info that
// comes only after the reader filled never arrives (said after 5 s), and a KEEP_LAST camera is
// not held back, its frames lost uncounted (said once such a publisher matches; README).
//
// The depth is used as received: it must be rectified (a driver's image_rect topic; what
// jpcr_dds_play publishes is), and its intrinsics are the camera_info's P, the rectified
// camera's (K when P is all zero). A camera_info with lens distortion D is logged once, as D is
// not applied.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"
#include "jpcr/io/log_budget.hpp"
#include "jpcr/quadric/frame.hpp"

namespace jpcr {

class DdsDepthSubscriber {
 public:
  /// `log` receives one line per rejected sample and per burst of dropped frames (default
  /// std::cerr); it is written from the caller's thread only.
  DdsDepthSubscriber(const DdsParticipant& participant, const DdsConfig& config,
                     std::ostream* log = nullptr);
  ~DdsDepthSubscriber();
  DdsDepthSubscriber(const DdsDepthSubscriber&) = delete;
  DdsDepthSubscriber& operator=(const DdsDepthSubscriber&) = delete;

  /// The next valid depth frame, waiting up to `timeout`; nullopt on timeout. A depth image that
  /// arrives before any camera_info waits (in the queue) for one. The first depth image that
  /// names its header.frame_id fixes the stream's camera: a depth image naming another is
  /// rejected, as a malformed one is. A camera_info in another frame than the depth is used (some
  /// drivers publish it so) and said once; the first camera_info that names its frame fixes
  /// that frame, and one of another is rejected.
  std::optional<Frame> wait_frame(std::chrono::milliseconds timeout);

  /// header.frame_id of the depth image of the frame wait_frame returned last ("" before one).
  const std::string& frame_id() const { return frame_id_; }

  std::size_t frames_received() const { return frames_; }
  std::size_t samples_rejected() const { return rejected_; }
  /// Depth images dropped from the full queue before the caller asked for them, plus those
  /// Cyclone reports lost in transport (sample lost status).
  std::size_t frames_dropped() const;
  /// Frames received and not yet returned by wait_frame (at a stop: left unprocessed). On the
  /// caller's thread, as wait_frame: at most twice image_history_depth (decoded ones waiting,
  /// and those the listener queued since; with input_keep_all, those still in the reader).
  std::size_t frames_waiting() const;
  /// Publishers matched on the depth topic.
  int matched() const;

 private:
  struct State;
  void process();
  void reject(const std::string& topic, const std::string& problem);
  // One camera per stream: a depth image naming another frame than the first named one is
  // rejected (an empty frame_id names none).
  bool of_this_camera(const std::string& frame_id);
  std::string other_camera(const std::string& frame_id) const;
  void log_incompatible(const std::string& topic, std::atomic<int>& policy);
  void log_camera_info_wait();
  void log_keep_last_publishers();
  static constexpr std::chrono::seconds kCameraInfoPatience{5};

  DdsConfig config_;
  std::ostream* log_;
  std::unique_ptr<State> state_;
  std::size_t frames_ = 0;
  std::string frame_id_;
  std::string camera_frame_id_;       // the stream's frame: the first one a depth image named
  std::string camera_info_frame_id_;  // the first camera_info's that named one
  std::size_t rejected_ = 0;
  std::size_t dropped_seen_ = 0;         // the drops process() has looked at
  std::size_t dropped_logged_ = 0;       // ... and those a log line counted
  LogBudget reject_lines_, drop_lines_;  // the first 10 lines of a kind, then one per 10 s
  bool distortion_logged_ = false;       // the note that D is not applied, once
  bool frame_mismatch_logged_ = false;   // the note that camera_info names another frame, once
  std::uint32_t lost_ = 0;
  // KEEP_ALL: since when depth images wait in the reader for a first camera_info, and whether
  // that was said (once, after kCameraInfoPatience).
  std::optional<std::chrono::steady_clock::time_point> waiting_for_camera_info_;
  bool camera_info_wait_logged_ = false;
  int publishers_seen_ = 0;  // KEEP_ALL: depth publishers at the last look
  bool keep_last_publisher_logged_ = false;
};

}  // namespace jpcr
