// The keyframe topic of the split deployment (jpcr_node --role frontend / backend): the front-end
// process writes each keyframe as a jpcr_msgs/Keyframe on PREFIX + "keyframe" (depth in 32FC1,
// lossless, with its camera, the front end's T_wc and ICP covariance, and the poses of the frames
// tracked since the previous keyframe), and an end-of-stream marker when it stops; the back-end
// process reads them.
//
// QoS: reliable, volatile, KEEP_ALL on both sides: a back end busy refining a window loses no
// keyframe (Cyclone keeps the unread samples; the writer blocks only when the reader stops
// acknowledging), so the back end sees exactly what the single-process pipeline would.
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"
#include "jpcr/io/dds/ros_messages.hpp"

namespace jpcr {

/// PREFIX + "keyframe".
std::string keyframe_topic_name(const DdsConfig& config);
/// Reliable, volatile, keep all.
DdsQos keyframe_topic_qos();

class DdsKeyframeWriter {
 public:
  DdsKeyframeWriter(const DdsParticipant& participant, const DdsConfig& config);

  /// Keyframe `frame_index` with the front end's pose and covariance, after the frames `tracked`
  /// since the previous keyframe.
  void publish(const Frame& frame, const StampedPose& pose, const Matrix6d& covariance,
               int frame_index, const Trajectory& tracked) const;
  /// The end-of-stream marker: `frames` tracked in all, `tracked` after the last keyframe.
  void publish_end(int frames, const Trajectory& tracked) const;

  /// Back ends matched.
  int matched() const { return writer_.matched(); }
  bool wait_matched(std::chrono::milliseconds timeout) const {
    return writer_.wait_matched(1, timeout);
  }
  /// Waits until the back ends acknowledged every keyframe (before exiting).
  bool flush(std::chrono::milliseconds timeout) const { return writer_.wait_for_acks(timeout); }

 private:
  DdsConfig config_;
  DdsWriter<RosKeyframe> writer_;
};

class DdsKeyframeReader {
 public:
  /// `log` receives one line per rejected sample (default std::cerr).
  DdsKeyframeReader(const DdsParticipant& participant, const DdsConfig& config,
                    std::ostream* log = nullptr);

  /// The next valid keyframe message (or end-of-stream marker), waiting up to `timeout`.
  std::optional<DecodedKeyframe> wait(std::chrono::milliseconds timeout);

  std::size_t samples_rejected() const { return rejected_; }
  /// Front ends matched.
  int matched() const { return reader_.matched(); }

 private:
  void poll();

  std::string topic_;
  RosImageLimits limits_;
  std::ostream* log_;
  DdsReader<RosKeyframe> reader_;
  std::deque<DecodedKeyframe> received_;
  std::size_t rejected_ = 0;
};

}  // namespace jpcr
