#include "jpcr/io/dds/dds_endpoint.hpp"

#include <algorithm>
#include <cstring>
#include <thread>
#include <vector>

namespace jpcr {

namespace {

// A QoS object, owned.
class Qos {
 public:
  explicit Qos(const DdsQos& q) : qos_(dds_create_qos()) {
    dds_qset_reliability(qos_, q.reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                         DDS_MSECS(q.max_blocking_ms));
    dds_qset_durability(
        qos_, q.transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
    if (q.keep_all) {
      dds_qset_history(qos_, DDS_HISTORY_KEEP_ALL, 0);
      if (q.max_samples > 0)
        dds_qset_resource_limits(qos_, q.max_samples, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
    } else {
      dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, q.depth);
      // What a transient-local writer keeps for late joiners is its durability service's
      // history, KEEP_LAST 1 unless set (as rmw_cyclonedds_cpp sets it): the same depth.
      if (q.transient_local)
        dds_qset_durability_service(qos_, 0, DDS_HISTORY_KEEP_LAST, q.depth, DDS_LENGTH_UNLIMITED,
                                    DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
    }
    const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};
    dds_qset_data_representation(qos_, 1, xcdr1);
    if (!q.user_data.empty()) dds_qset_userdata(qos_, q.user_data.data(), q.user_data.size());
  }
  ~Qos() { dds_delete_qos(qos_); }
  Qos(const Qos&) = delete;
  Qos& operator=(const Qos&) = delete;
  const dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

constexpr std::chrono::milliseconds kMatchPollInterval{5};

}  // namespace

DdsEntity& DdsEntity::operator=(DdsEntity&& other) noexcept {
  if (this != &other) {
    reset();
    handle_ = other.handle_;
    other.handle_ = 0;
  }
  return *this;
}

void DdsEntity::reset() {
  if (handle_ > 0) dds_delete(handle_);
  handle_ = 0;
}

DdsEndpoint::DdsEndpoint(const DdsParticipant& participant, const std::string& topic,
                         const dds_topic_descriptor_t& type, const DdsQos& qos, Kind kind,
                         const dds_listener_t* listener)
    : name_(topic), kind_(kind) {
  if (!qos.keep_all && qos.depth < 1)
    throw DdsError("topic " + topic + ": history depth must be at least 1");
  if (qos.max_samples < 0 || qos.max_blocking_ms < 0)
    throw DdsError("topic " + topic + ": negative resource limit or blocking time");
  const Qos q(qos);
  topic_ = DdsEntity(
      check_dds(dds_create_topic(participant.handle(), &type, topic.c_str(), nullptr, nullptr),
                "dds_create_topic(" + topic + ")"));
  if (kind == Kind::kWriter) {
    endpoint_ =
        DdsEntity(check_dds(dds_create_writer(participant.handle(), topic_.get(), q.get(), nullptr),
                            "dds_create_writer(" + topic + ")"));
    return;
  }
  endpoint_ =
      DdsEntity(check_dds(dds_create_reader(participant.handle(), topic_.get(), q.get(), listener),
                          "dds_create_reader(" + topic + ")"));
  condition_ = DdsEntity(check_dds(dds_create_readcondition(endpoint_.get(), DDS_ANY_STATE),
                                   "dds_create_readcondition(" + topic + ")"));
  waitset_ = DdsEntity(check_dds(dds_create_waitset(participant.handle()), "dds_create_waitset"));
  check_dds(dds_waitset_attach(waitset_.get(), condition_.get(), 0), "dds_waitset_attach");
}

int DdsEndpoint::matched() const {
  if (kind_ == Kind::kWriter) {
    dds_publication_matched_status_t status;
    check_dds(dds_get_publication_matched_status(endpoint_.get(), &status),
              "dds_get_publication_matched_status(" + name_ + ")");
    return static_cast<int>(status.current_count);
  }
  dds_subscription_matched_status_t status;
  check_dds(dds_get_subscription_matched_status(endpoint_.get(), &status),
            "dds_get_subscription_matched_status(" + name_ + ")");
  return static_cast<int>(status.current_count);
}

// The matched endpoints of the other side (a writer's readers, a reader's writers) whose QoS
// `counts` accepts.
int DdsEndpoint::count_matched(const std::function<bool(const dds_qos_t*)>& counts) const {
  const bool writer = kind_ == Kind::kWriter;
  std::vector<dds_instance_handle_t> handles(static_cast<std::size_t>(matched()) + 4);
  const dds_return_t n = check_dds(
      writer ? dds_get_matched_subscriptions(endpoint_.get(), handles.data(), handles.size())
             : dds_get_matched_publications(endpoint_.get(), handles.data(), handles.size()),
      "dds_get_matched_" + std::string(writer ? "subscriptions(" : "publications(") + name_ + ")");
  int count = 0;
  for (dds_return_t i = 0; i < std::min<dds_return_t>(n, handles.size()); ++i) {
    const dds_instance_handle_t h = handles[static_cast<std::size_t>(i)];
    // NULL when the endpoint went away meanwhile.
    dds_builtintopic_endpoint_t* other = writer
                                             ? dds_get_matched_subscription_data(endpoint_.get(), h)
                                             : dds_get_matched_publication_data(endpoint_.get(), h);
    if (other == nullptr) continue;
    if (counts(other->qos)) ++count;
    dds_builtintopic_free_endpoint(other);
  }
  return count;
}

int DdsEndpoint::matched_readers_with(const std::string& user_data) const {
  if (kind_ != Kind::kWriter) throw DdsError(name_ + ": matched_readers_with needs a writer");
  return count_matched([&](const dds_qos_t* qos) {
    void* value = nullptr;
    std::size_t size = 0;
    const bool same = dds_qget_userdata(qos, &value, &size) && size == user_data.size() &&
                      std::memcmp(value, user_data.data(), size) == 0;
    dds_free(value);
    return same;
  });
}

int DdsEndpoint::matched_keep_last_writers() const {
  if (kind_ != Kind::kReader) throw DdsError(name_ + ": matched_keep_last_writers needs a reader");
  return count_matched([](const dds_qos_t* qos) {
    dds_history_kind_t kind = DDS_HISTORY_KEEP_LAST;  // the default, when the QoS does not say
    int32_t depth = 0;
    dds_qget_history(qos, &kind, &depth);
    return kind == DDS_HISTORY_KEEP_LAST;
  });
}

bool poll_until(const std::function<bool()>& done, std::chrono::steady_clock::time_point deadline,
                const std::function<bool()>& keep_waiting) {
  while (!done()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    if (keep_waiting && !keep_waiting()) return false;
    std::this_thread::sleep_for(kMatchPollInterval);
  }
  return true;
}

bool DdsEndpoint::wait_matched(int count, std::chrono::steady_clock::time_point deadline,
                               const std::function<bool()>& keep_waiting) const {
  return poll_until([&] { return matched() >= count; }, deadline, keep_waiting);
}

bool DdsEndpoint::wait_for_acks(std::chrono::milliseconds timeout) const {
  const dds_return_t r = dds_wait_for_acks(endpoint_.get(), DDS_MSECS(timeout.count()));
  if (r == DDS_RETCODE_TIMEOUT) return false;
  check_dds(r, "dds_wait_for_acks(" + name_ + ")");
  return true;
}

void DdsEndpoint::write_sample(const void* sample) const {
  check_dds(dds_write(endpoint_.get(), sample), "dds_write(" + name_ + ")");
}

bool DdsEndpoint::try_write_sample(const void* sample) const {
  const dds_return_t r = dds_write(endpoint_.get(), sample);
  if (r == DDS_RETCODE_TIMEOUT) return false;
  check_dds(r, "dds_write(" + name_ + ")");
  return true;
}

bool DdsEndpoint::wait_data(std::chrono::nanoseconds timeout) const {
  const dds_return_t n = dds_waitset_wait(waitset_.get(), nullptr, 0, timeout.count());
  return check_dds(n, "dds_waitset_wait(" + name_ + ")") > 0;
}

}  // namespace jpcr
