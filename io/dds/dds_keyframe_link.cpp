#include "jpcr/io/dds/dds_keyframe_link.hpp"

#include <chrono>
#include <iostream>
#include <thread>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

std::string keyframe_topic_name(const DdsConfig& config) {
  return config.topic_prefix + "keyframe";
}

DdsQos keyframe_topic_qos() {
  DdsQos qos;
  qos.reliable = true;
  qos.keep_all = true;
  qos.max_blocking_ms = kKeyframeWriteTry;
  return qos;
}

DdsQos keyframe_reader_qos(const DdsConfig& config) {
  DdsQos qos = keyframe_topic_qos();
  qos.max_samples = config.keyframe_queue;
  qos.user_data = kBackEndUserData;
  return qos;
}

int DdsKeyframeWriter::matched() const {
  return writer_.matched_readers_with(kBackEndUserData);
}

DdsKeyframeWriter::DdsKeyframeWriter(const DdsParticipant& participant, const DdsConfig& config)
    : config_(config), writer_(participant, keyframe_topic_name(config), keyframe_topic_qos()) {}

namespace {

constexpr int kMatchPoll = 5;  // ms between two looks at the matched back ends

// Calls try_once, which blocks for at most one try of kKeyframeWriteTry ms, until it succeeds;
// between tries asks keep_waiting (empty: waits as long as it takes) with the seconds waited.
template <class TryOnce>
bool retry_until(const TryOnce& try_once, const KeepWaiting& keep_waiting) {
  const auto start = std::chrono::steady_clock::now();
  while (!try_once()) {
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (keep_waiting && !keep_waiting(waited)) return false;
  }
  return true;
}

}  // namespace

// Each try blocks up to the QoS's max_blocking_time while the back end's queue is full.
bool DdsKeyframeWriter::write(const RosKeyframe& message, const KeepWaiting& keep_waiting) const {
  return retry_until([&] { return writer_.try_write(message); }, keep_waiting);
}

bool DdsKeyframeWriter::flush(const KeepWaiting& keep_waiting) const {
  return retry_until(
      [&] { return writer_.wait_for_acks(std::chrono::milliseconds(kKeyframeWriteTry)); },
      keep_waiting);
}

bool DdsKeyframeWriter::wait_for_back_ends(bool present, const KeepWaiting& keep_waiting) const {
  return retry_until(
      [&] {
        if ((matched() > 0) == present) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(kMatchPoll));
        return false;
      },
      keep_waiting);
}

bool DdsKeyframeWriter::wait_matched(std::chrono::milliseconds timeout,
                                     const KeepWaiting& keep_waiting) const {
  return wait_for_back_ends(true, [&](double waited) {
    return waited * 1000.0 < timeout.count() && (!keep_waiting || keep_waiting(waited));
  });
}

bool DdsKeyframeWriter::wait_until_unmatched(const KeepWaiting& keep_waiting) const {
  return wait_for_back_ends(false, keep_waiting);
}

bool DdsKeyframeWriter::publish(const Frame& frame, const StampedPose& pose,
                                const Matrix6d& covariance, int frame_index,
                                const Trajectory& tracked, const KeepWaiting& keep_waiting) const {
  // 32FC1 carries the float depth bit for bit; 16UC1 would round it to millimetres.
  const KeyframeMessage message(frame, pose, covariance, DepthEncoding::kMetres32,
                                config_.world_frame_id, config_.camera_frame_id, frame_index,
                                tracked);
  return write(message.message(), keep_waiting);
}

bool DdsKeyframeWriter::publish_end(int frames, const Trajectory& tracked,
                                    const KeepWaiting& keep_waiting) const {
  const KeyframeMessage message(frames, tracked, config_.world_frame_id);
  return write(message.message(), keep_waiting);
}

DdsKeyframeReader::DdsKeyframeReader(const DdsParticipant& participant, const DdsConfig& config,
                                     std::ostream* log)
    : topic_(keyframe_topic_name(config)),
      log_(log ? log : &std::cerr),
      reader_(participant, topic_, keyframe_reader_qos(config)) {
  limits_.max_bytes = config.max_image_bytes();
  limits_.max_side = static_cast<std::uint32_t>(config.max_image_side);
}

void DdsKeyframeReader::poll() {
  reader_.take([&](const RosKeyframe& m) {
    try {
      received_.push_back(decode_keyframe(m, limits_));
    } catch (const InputError& e) {
      ++rejected_;
      std::size_t left_out = 0;  // a broken front end must not flood the log
      if (reject_lines_.allow(left_out))
        *log_ << "jpcr dds: " << topic_ << ": rejected sample: " << e.what()
              << LogBudget::note(left_out) << std::endl;
    }
  });
}

std::optional<DecodedKeyframe> DdsKeyframeReader::wait(std::chrono::milliseconds timeout) {
  if (received_.empty()) poll();
  if (received_.empty() && reader_.wait(timeout)) poll();
  if (received_.empty()) return std::nullopt;
  DecodedKeyframe k = std::move(received_.front());
  received_.pop_front();
  return k;
}

}  // namespace jpcr
