// The keyframe topic of the split deployment (jpcr_node --role frontend / backend): the front-end
// process writes each keyframe as a jpcr_msgs/Keyframe on PREFIX + "keyframe" (depth in 32FC1,
// lossless, with its camera, the front end's T_wc and ICP covariance, and the poses of the frames
// tracked since the previous keyframe), and an end-of-stream marker when it stops; the back-end
// process reads them.
//
// QoS: reliable, volatile, KEEP_ALL on both sides: a back end busy refining a window loses no
// keyframe, so it sees exactly what the single-process pipeline would. Its reader holds at most
// dds.keyframe_queue unread keyframes (a resource limit, so memory stays bounded when the back
// end is slower than the front end); when they are all waiting, the reader stops acknowledging
// and the front end's publish waits until the back end takes one: the front end is then paced by
// the back end (its camera queue drops frames meanwhile, counted and logged).
//
// Cyclone acknowledges a keyframe that arrives at a full queue and holds it for delivery, but
// only while the writer exists: a front end that exited right after its last write would lose the
// keyframes still held (measured with a queue of 1). So the front end, once the back ends
// acknowledged the end of stream, waits until they are gone (wait_until_unmatched): a jpcr back
// end exits after the end of stream. Back ends are told from other readers of the topic by their
// reader's USER_DATA, so a jpcr_dds_echo on it holds nothing up.
//
// Run the two in separate processes, as jpcr_node does. In one process Cyclone delivers locally
// and a write that times out on a full reader is not delivered at all: publish() then writes it
// again, which a remote reader of the same writer would receive twice.
#pragma once

#include <chrono>
#include <cstddef>
#include <deque>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"
#include "jpcr/io/dds/ros_messages.hpp"
#include "jpcr/io/log_budget.hpp"

namespace jpcr {

/// PREFIX + "keyframe".
std::string keyframe_topic_name(const DdsConfig& config);
/// How long one write waits for room in the back end's queue, ms: keep_waiting's period.
constexpr int kKeyframeWriteTry = 100;

/// The writer's QoS: reliable, volatile, keep all, writes retried every kKeyframeWriteTry ms.
DdsQos keyframe_topic_qos();
/// The reader's: the same, holding at most config.keyframe_queue unread keyframes, with
/// USER_DATA kBackEndUserData.
DdsQos keyframe_reader_qos(const DdsConfig& config);
/// What a jpcr back end's keyframe reader says it is (USER_DATA).
inline constexpr const char* kBackEndUserData = "jpcr back end";

/// Asked every kKeyframeWriteTry ms while a publish waits for room in the back end's queue, with
/// the seconds waited so far; false gives the sample up.
using KeepWaiting = std::function<bool(double waited_s)>;

class DdsKeyframeWriter {
 public:
  DdsKeyframeWriter(const DdsParticipant& participant, const DdsConfig& config);

  /// Keyframe `frame_index` with the front end's pose and covariance, after the frames `tracked`
  /// since the previous keyframe. While the back end's queue is full it waits, asking
  /// `keep_waiting` (empty: waits as long as it takes); false when it gave the keyframe up.
  bool publish(const Frame& frame, const StampedPose& pose, const Matrix6d& covariance,
               int frame_index, const Trajectory& tracked,
               const KeepWaiting& keep_waiting = {}) const;
  /// The camera frame the keyframes' depth and camera_info carry (the received depth's); an
  /// empty `id` keeps the current one (DdsConfig::camera_frame_id at first).
  void set_camera_frame_id(const std::string& id) {
    if (!id.empty()) config_.camera_frame_id = id;
  }
  /// The end-of-stream marker: `frames` tracked in all, `tracked` after the last keyframe.
  bool publish_end(int frames, const Trajectory& tracked,
                   const KeepWaiting& keep_waiting = {}) const;

  /// jpcr back ends matched: readers whose USER_DATA is kBackEndUserData, so that another
  /// reader of the topic (jpcr_dds_echo, a recorder) neither starts nor holds up the stream.
  int matched() const;
  /// Waits until a back end is matched; false on timeout, or once `keep_waiting` (when given)
  /// says false (a stop request).
  bool wait_matched(std::chrono::milliseconds timeout, const KeepWaiting& keep_waiting = {}) const;
  /// Waits until the back ends acknowledged every keyframe (before exiting): a back end
  /// acknowledges a keyframe once its queue has room for it, so this waits as publish does.
  bool flush(const KeepWaiting& keep_waiting) const;
  /// Waits until no back end is matched any more (they finished), asking keep_waiting between
  /// looks; false when it gave up.
  bool wait_until_unmatched(const KeepWaiting& keep_waiting) const;

 private:
  bool write(const RosKeyframe& message, const KeepWaiting& keep_waiting) const;
  bool wait_for_back_ends(bool present, const KeepWaiting& keep_waiting) const;

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
  LogBudget reject_lines_;
  std::size_t rejected_ = 0;
};

}  // namespace jpcr
