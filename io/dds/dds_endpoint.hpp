// Typed DDS writers and readers over Cyclone's C API: DdsWriter<Msg> and DdsReader<Msg> for an
// idlc-generated C struct Msg whose descriptor DdsType<Msg> names (io/dds/ros_messages.hpp).
// Topics are keyless and written as XCDR1, which is what ROS 2 (rmw_cyclonedds) expects.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>

#include <dds/dds.h>

#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/dds_participant.hpp"

namespace jpcr {

/// Maps a generated message type to its topic descriptor; specialised per type.
template <typename Msg>
struct DdsType;

/// An owned Cyclone entity (topic, writer, reader, condition, waitset); deleted with its
/// children on destruction. Movable, not copyable.
class DdsEntity {
 public:
  DdsEntity() = default;
  explicit DdsEntity(dds_entity_t handle) : handle_(handle) {}
  ~DdsEntity() { reset(); }
  DdsEntity(DdsEntity&& other) noexcept : handle_(other.handle_) { other.handle_ = 0; }
  DdsEntity& operator=(DdsEntity&& other) noexcept;
  DdsEntity(const DdsEntity&) = delete;
  DdsEntity& operator=(const DdsEntity&) = delete;

  dds_entity_t get() const { return handle_; }
  void reset();

 private:
  dds_entity_t handle_ = 0;
};

/// Polls `done` every few milliseconds until it is true (true), `deadline` passes or
/// keep_waiting (when given, e.g. "no stop signal yet") says no (false). Cyclone reports
/// discovery as a status to read, so the waits for matching endpoints poll it.
bool poll_until(const std::function<bool()>& done, std::chrono::steady_clock::time_point deadline,
                const std::function<bool()>& keep_waiting = {});

/// A topic plus a writer or a reader on it (the untyped part of DdsWriter and DdsReader).
class DdsEndpoint {
 public:
  enum class Kind { kWriter, kReader };
  /// `listener` (a reader's, may be null) is copied; its callbacks run on Cyclone's threads.
  DdsEndpoint(const DdsParticipant& participant, const std::string& topic,
              const dds_topic_descriptor_t& type, const DdsQos& qos, Kind kind,
              const dds_listener_t* listener = nullptr);

  const std::string& topic() const { return name_; }
  dds_entity_t handle() const { return endpoint_.get(); }
  /// Matched remote endpoints (readers of a writer, writers of a reader).
  int matched() const;
  /// A writer: its matched readers whose USER_DATA (DdsQos::user_data) is `user_data`.
  int matched_readers_with(const std::string& user_data) const;
  /// A reader: its matched writers whose history is KEEP_LAST (which a KEEP_ALL reader's
  /// resource limit cannot hold back).
  int matched_keep_last_writers() const;
  /// Waits until at least `count` endpoints are matched by `deadline`; false on timeout, or as
  /// soon as keep_waiting (when given, e.g. "no stop signal yet") says no.
  bool wait_matched(int count, std::chrono::steady_clock::time_point deadline,
                    const std::function<bool()>& keep_waiting = {}) const;
  bool wait_matched(int count, std::chrono::milliseconds timeout) const {
    return wait_matched(count, std::chrono::steady_clock::now() + timeout);
  }
  /// A writer: waits until matched reliable readers acknowledged every sample; false on timeout.
  bool wait_for_acks(std::chrono::milliseconds timeout) const;

 protected:
  void write_sample(const void* sample) const;
  /// false when the write timed out: a reliable reader's resource limit is full (after the QoS's
  /// max_blocking_ms); the sample was not written and may be written again.
  bool try_write_sample(const void* sample) const;
  /// Waits for data; true when there is some.
  bool wait_data(std::chrono::nanoseconds timeout) const;

  int count_matched(const std::function<bool(const dds_qos_t*)>& counts) const;

  std::string name_;
  Kind kind_;
  DdsEntity topic_, endpoint_, condition_, waitset_;
};

template <typename Msg>
class DdsWriter : public DdsEndpoint {
 public:
  DdsWriter(const DdsParticipant& participant, const std::string& topic, const DdsQos& qos)
      : DdsEndpoint(participant, topic, DdsType<Msg>::descriptor(), qos, Kind::kWriter) {}
  /// Publishes a sample; throws DdsError when Cyclone refuses it.
  void write(const Msg& sample) const { write_sample(&sample); }
  /// write, or false after max_blocking_ms while a reliable reader's resource limit is full.
  bool try_write(const Msg& sample) const { return try_write_sample(&sample); }
};

/// Takes every available sample of `reader`, or the oldest `max`, and calls
/// on_sample(const Msg&) on each valid one; the sample is a loan valid only during the call.
/// Returns the number of samples taken, valid or not (`taken`, when given) and of valid ones. For
/// DdsReader::take and for listener callbacks, which get the reader's handle.
template <typename Msg, typename OnSample>
std::size_t take_samples(dds_entity_t reader, OnSample&& on_sample,
                         std::size_t max = static_cast<std::size_t>(-1),
                         std::size_t* taken = nullptr) {
  constexpr std::size_t kBatch = 8;  // samples per loan
  std::size_t valid = 0;
  if (taken) *taken = 0;
  for (;;) {
    const std::size_t batch = std::min(kBatch, max);
    if (batch == 0) return valid;
    void* samples[kBatch] = {};
    dds_sample_info_t infos[kBatch];
    const dds_return_t n = dds_take(reader, samples, infos, batch, static_cast<uint32_t>(batch));
    if (n <= 0) return valid;
    max -= static_cast<std::size_t>(n);
    if (taken) *taken += static_cast<std::size_t>(n);
    struct Loan {
      dds_entity_t reader;
      void** samples;
      dds_return_t n;
      ~Loan() { dds_return_loan(reader, samples, n); }
    } loan{reader, samples, n};
    for (dds_return_t i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      ++valid;
      on_sample(*static_cast<const Msg*>(samples[i]));
    }
    if (static_cast<std::size_t>(n) < batch) return valid;
  }
}

template <typename Msg>
class DdsReader : public DdsEndpoint {
 public:
  DdsReader(const DdsParticipant& participant, const std::string& topic, const DdsQos& qos,
            const dds_listener_t* listener = nullptr)
      : DdsEndpoint(participant, topic, DdsType<Msg>::descriptor(), qos, Kind::kReader, listener) {}

  /// Waits up to `timeout` for samples.
  bool wait(std::chrono::nanoseconds timeout) const { return wait_data(timeout); }

  /// take_samples on this reader.
  template <typename OnSample>
  std::size_t take(OnSample&& on_sample) const {
    return take_samples<Msg>(handle(), std::forward<OnSample>(on_sample));
  }
};

}  // namespace jpcr
