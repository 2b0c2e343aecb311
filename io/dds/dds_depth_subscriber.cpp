#include "jpcr/io/dds/dds_depth_subscriber.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <deque>
#include <iostream>
#include <mutex>
#include <utility>
#include <vector>

#include <dds/ddsi/ddsi_serdata.h>

#include "jpcr/io/dds/ros_messages.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// A depth image as taken from Cyclone: a checked copy, or the problem that rejects it.
struct ReceivedImage {
  RosImageBuffer image;
  RosStamp stamp;
  std::string frame_id;
  std::string problem;
};

// A camera_info as taken from Cyclone, or the problem that rejects it.
struct ReceivedCamera {
  std::optional<CameraIntrinsics> camera;
  bool lens_distortion = false;  // D has a non-zero term (not applied: logged once)
  std::string frame_id;
  std::string problem;
};

// Owns a listener object; the reader copies it at creation.
struct Listener {
  Listener(void* arg, dds_on_data_available_fn on_data,
           dds_on_requested_incompatible_qos_fn on_incompatible)
      : handle(dds_create_listener(arg)) {
    dds_lset_data_available(handle, on_data);
    dds_lset_requested_incompatible_qos(handle, on_incompatible);
  }
  ~Listener() { dds_delete_listener(handle); }
  dds_listener_t* handle;
};

}  // namespace

struct DdsDepthSubscriber::State {
  State(const DdsParticipant& p, const DdsConfig& c)
      : queue_depth(static_cast<std::size_t>(c.image_history_depth)),
        keep_all(c.input_keep_all),
        limits(limits_of(c)),
        camera_listener(this, on_camera_info, on_camera_incompatible),
        depth_listener(this, on_depth, on_depth_incompatible),
        camera_info(p, c.camera_info_topic, c.camera_info_qos(), camera_listener.handle),
        depth(p, c.depth_topic, c.depth_qos(), depth_listener.handle) {}

  static RosImageLimits limits_of(const DdsConfig& c) {
    RosImageLimits l;
    l.max_bytes = c.max_image_bytes();
    l.max_side = static_cast<std::uint32_t>(c.max_image_side);
    return l;
  }

  // Cyclone's receive thread: take at once, so that the reader's history never overflows; with
  // KEEP_ALL the images stay in it (its resource limit holds the camera back) until the caller
  // has room for them (take_waiting_depth).
  static void on_depth(dds_entity_t reader, void* arg) {
    State& s = *static_cast<State*>(arg);
    try {
      if (s.keep_all) {
        const std::lock_guard<std::mutex> lock(s.mutex);
        s.depth_pending = true;
        s.arrived.notify_all();
      } else {
        take_depth(reader, s);
      }
    } catch (...) {  // bad_alloc in the queue, a failed lock: nothing may leave Cyclone's thread
      s.lost_in_listener.fetch_add(1);
    }
  }

  // A received depth image, checked, onto the queue (KEEP_LAST: the oldest goes, counted).
  static void queue_image(const RosImage& m, State& s) {
    ReceivedImage r;
    const RosImageView view = image_view_of(m);
    r.stamp = stamp_of(m.header);
    try {
      if (m.header.frame_id != nullptr) r.frame_id = m.header.frame_id;
    } catch (const std::exception&) {  // bad_alloc: nothing may leave Cyclone's thread
    }
    try {
      check_image_layout(view, {{"16UC1", 2}, {"32FC1", 4}}, s.limits);
      r.image.height = view.height;
      r.image.width = view.width;
      r.image.encoding = std::string(view.encoding);
      r.image.step = view.step;
      r.image.data.assign(view.data, view.data + view.size);
    } catch (const std::exception& e) {  // also bad_alloc: nothing may leave Cyclone's thread
      r.problem = e.what();
    }
    const std::lock_guard<std::mutex> lock(s.mutex);
    s.images.push_back(std::move(r));
    if (s.images.size() > s.queue_depth) {
      s.images.pop_front();
      ++s.dropped;
    }
    s.arrived.notify_all();
  }

  // Takes the oldest `max` images (all by default) onto the queue; returns how many it took.
  static std::size_t take_depth(dds_entity_t reader, State& s,
                                std::size_t max = static_cast<std::size_t>(-1)) {
    std::size_t taken = 0;
    take_samples<RosImage>(
        reader, [&](const RosImage& m) { queue_image(m, s); }, max, &taken);
    return taken;
  }

  // KEEP_ALL: the caller's thread takes as many waiting images as the queue has room for, once
  // there is a camera_info to decode them with (until then they wait in the reader).
  void take_waiting_depth(std::size_t decoded) {
    if (!keep_all || !camera) return;
    std::size_t room = 0;
    {
      const std::lock_guard<std::mutex> lock(mutex);
      if (decoded + images.size() >= queue_depth) return;
      room = queue_depth - decoded - images.size();
      depth_pending = false;  // before the take: an image arriving during it sets it again
    }
    if (take_depth(depth.handle(), *this, room) == room) {
      const std::lock_guard<std::mutex> lock(mutex);
      depth_pending = true;  // there may be more
    }
  }

  static void on_camera_info(dds_entity_t reader, void* arg) {
    State& s = *static_cast<State*>(arg);
    try {
      take_cameras(reader, s);
    } catch (...) {  // as on_depth
      s.lost_in_listener.fetch_add(1);
    }
  }

  static void take_cameras(dds_entity_t reader, State& s) {
    take_samples<RosCameraInfoMsg>(reader, [&](const RosCameraInfoMsg& m) {
      ReceivedCamera r;
      try {
        if (m.header.frame_id != nullptr) r.frame_id = m.header.frame_id;
        const RosCameraInfo info = camera_info_of(m);
        r.camera = decode_camera_info(info, s.limits);
        r.lens_distortion = lens_distortion(info);
      } catch (const std::exception& e) {
        r.problem = e.what();
      }
      const std::lock_guard<std::mutex> lock(s.mutex);
      s.cameras.push_back(std::move(r));
      // Only the newest camera counts: while the caller is busy the queue keeps the last few
      // (an older sample dropped here is not logged).
      if (s.cameras.size() > kCameraQueue) s.cameras.pop_front();
      s.arrived.notify_all();
    });
  }

  // A publisher this reader cannot match (a best-effort camera against the reliable default):
  // Cyclone says so only here, so the policy is kept for process() to log.
  static void on_incompatible(State& s, std::atomic<int>& policy,
                              const dds_requested_incompatible_qos_status_t& status) {
    policy = static_cast<int>(status.last_policy_id);
    const std::lock_guard<std::mutex> lock(s.mutex);
    s.arrived.notify_all();
  }
  static void on_depth_incompatible(dds_entity_t, const dds_requested_incompatible_qos_status_t st,
                                    void* arg) {
    State& s = *static_cast<State*>(arg);
    on_incompatible(s, s.depth_incompatible, st);
  }
  static void on_camera_incompatible(dds_entity_t, const dds_requested_incompatible_qos_status_t st,
                                     void* arg) {
    State& s = *static_cast<State*>(arg);
    on_incompatible(s, s.camera_incompatible, st);
  }

  const std::size_t queue_depth;
  const bool keep_all;  // DdsConfig::input_keep_all
  const RosImageLimits limits;
  std::atomic<int> depth_incompatible{kNoPolicy}, camera_incompatible{kNoPolicy};
  static constexpr int kNoPolicy = -1;
  std::mutex mutex;  // guards images, cameras, dropped, depth_pending
  std::condition_variable arrived;
  bool depth_pending = false;  // KEEP_ALL: images may wait in the reader
  std::deque<ReceivedImage> images;
  std::deque<ReceivedCamera> cameras;
  static constexpr std::size_t kCameraQueue = 8;
  std::size_t dropped = 0;
  // Listener calls that threw (each may lose samples, depth or camera_info; counted with the
  // dropped frames, as a lower bound).
  std::atomic<std::size_t> lost_in_listener{0};
  // The caller's thread only.
  std::optional<CameraIntrinsics> camera;
  std::deque<Frame> frames;
  std::deque<std::string> frame_ids;  // header.frame_id of each of `frames`
  // Declared last, deleted first: no callback runs once the members above go.
  Listener camera_listener, depth_listener;
  DdsReader<RosCameraInfoMsg> camera_info;
  DdsReader<RosImage> depth;
};

DdsDepthSubscriber::DdsDepthSubscriber(const DdsParticipant& participant, const DdsConfig& config,
                                       std::ostream* log)
    : config_(config),
      log_(log ? log : &std::cerr),
      state_(std::make_unique<State>(participant, config)) {}

DdsDepthSubscriber::~DdsDepthSubscriber() = default;

namespace {

// KEEP_ALL: the depth samples still in the reader (at most its resource limit, `limit`), which
// take_waiting_depth has not taken yet. Read as serialised data, not decoded: marking them read
// changes nothing, since take takes read and unread samples alike.
std::size_t samples_in_reader(dds_entity_t reader, std::size_t limit) {
  std::vector<ddsi_serdata*> data(limit, nullptr);
  std::vector<dds_sample_info_t> infos(limit);
  const dds_return_t n =
      dds_readcdr(reader, data.data(), static_cast<uint32_t>(limit), infos.data(), DDS_ANY_STATE);
  std::size_t valid = 0;
  for (dds_return_t i = 0; i < n; ++i) {
    if (infos[static_cast<std::size_t>(i)].valid_data) ++valid;
    if (data[static_cast<std::size_t>(i)] != nullptr)
      ddsi_serdata_unref(data[static_cast<std::size_t>(i)]);
  }
  return valid;
}

}  // namespace

std::size_t DdsDepthSubscriber::frames_waiting() const {
  State& s = *state_;
  std::size_t waiting = 0;
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    waiting = s.frames.size() + static_cast<std::size_t>(std::count_if(
                                    s.images.begin(), s.images.end(),
                                    [](const ReceivedImage& r) { return r.problem.empty(); }));
  }
  if (s.keep_all) waiting += samples_in_reader(s.depth.handle(), s.queue_depth);
  return waiting;
}

int DdsDepthSubscriber::matched() const {
  return state_->depth.matched();
}

std::size_t DdsDepthSubscriber::frames_dropped() const {
  const std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->dropped + state_->lost_in_listener.load() + lost_;
}

namespace {

// What a reader that cannot match a publisher should tell the user (Cyclone's last policy id).
std::string incompatible_qos_note(int policy) {
  switch (policy) {
    case DDS_RELIABILITY_QOS_POLICY_ID:
      return "its reliability: a best-effort publisher (a ROS sensor-data camera) needs "
             "dds: {input_reliability: best_effort}";
    case DDS_DURABILITY_QOS_POLICY_ID:
      return "its durability";
    case DDS_DATA_REPRESENTATION_QOS_POLICY_ID:
      return "its data representation: jpcr reads XCDR1, as ROS 2 writes it";
    default:
      return "QoS policy " + std::to_string(policy);
  }
}

}  // namespace

void DdsDepthSubscriber::log_incompatible(const std::string& topic, std::atomic<int>& policy) {
  const int p = policy.exchange(State::kNoPolicy);
  if (p == State::kNoPolicy) return;
  *log_ << "jpcr dds: " << topic << ": a publisher offers a QoS this reader cannot match, "
        << incompatible_qos_note(p) << "; its samples do not arrive" << std::endl;
}

void DdsDepthSubscriber::reject(const std::string& topic, const std::string& problem) {
  ++rejected_;
  std::size_t left_out = 0;
  if (reject_lines_.allow(left_out))
    *log_ << "jpcr dds: " << topic << ": rejected sample: " << problem << LogBudget::note(left_out)
          << std::endl;
}

bool DdsDepthSubscriber::of_this_camera(const std::string& frame_id) {
  if (frame_id.empty() || frame_id == camera_frame_id_) return true;
  if (!camera_frame_id_.empty()) return false;
  camera_frame_id_ = frame_id;  // the first depth image that names its frame fixes the stream's
  return true;
}

std::string DdsDepthSubscriber::other_camera(const std::string& frame_id) const {
  return "header.frame_id '" + frame_id + "' is not the stream's '" + camera_frame_id_ +
         "' (a second camera on the topic, or a renamed one: restart to follow it)";
}

// KEEP_ALL: depth images that wait in the reader for a first camera_info hold Cyclone's receive
// thread, and with it any camera_info sent later; said once, since the node then waits silently.
void DdsDepthSubscriber::log_camera_info_wait() {
  State& s = *state_;
  bool waiting = false;
  if (s.keep_all && !s.camera) {
    const std::lock_guard<std::mutex> lock(s.mutex);
    waiting = s.depth_pending;
  }
  if (!waiting) {
    waiting_for_camera_info_.reset();
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  if (!waiting_for_camera_info_) waiting_for_camera_info_ = now;
  if (camera_info_wait_logged_ || now - *waiting_for_camera_info_ < kCameraInfoPatience) return;
  camera_info_wait_logged_ = true;
  *log_ << "jpcr dds: " << config_.depth_topic << ": depth images wait for a camera_info on "
        << config_.camera_info_topic
        << "; with dds.input_history: keep_all they hold back all input of this process, and a "
           "camera_info sent from now on may not get through (publish it before the depth, or "
           "use keep_last)"
        << std::endl;
}

// KEEP_ALL: a KEEP_LAST publisher is not held back, and Cyclone does not report the images it
// drops for want of room (30 played, 8 processed, 0 counted): said once, when one matches.
void DdsDepthSubscriber::log_keep_last_publishers() {
  State& s = *state_;
  if (!s.keep_all || keep_last_publisher_logged_) return;
  const int publishers = s.depth.matched();
  if (publishers == publishers_seen_) return;
  publishers_seen_ = publishers;
  if (publishers == 0 || s.depth.matched_keep_last_writers() == 0) return;
  keep_last_publisher_logged_ = true;
  *log_ << "jpcr dds: " << config_.depth_topic
        << ": a publisher keeps only its last images (KEEP_LAST): dds.input_history: keep_all "
           "cannot hold it back, and the frames it sends while the queue is full are lost "
           "without being counted as dropped (publish with KEEP_ALL, as jpcr_dds_play does with "
           "the same setting, or use keep_last)"
        << std::endl;
}

// Decodes what the listeners queued (camera_info first, as a camera driver publishes it first),
// outside the lock so that Cyclone's receive thread never waits for a decode.
void DdsDepthSubscriber::process() {
  State& s = *state_;
  log_incompatible(config_.depth_topic, s.depth_incompatible);
  log_incompatible(config_.camera_info_topic, s.camera_incompatible);
  std::deque<ReceivedCamera> cameras;
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    cameras.swap(s.cameras);
  }
  for (const ReceivedCamera& c : cameras) {
    // The first camera_info that names its frame fixes the camera_info's frame (which may differ
    // from the depth's); one of another frame is a second camera's.
    if (c.camera && !c.frame_id.empty() && !camera_info_frame_id_.empty() &&
        c.frame_id != camera_info_frame_id_) {
      reject(config_.camera_info_topic, "header.frame_id '" + c.frame_id +
                                            "' is not the stream's camera_info frame '" +
                                            camera_info_frame_id_ + "' (a second camera?)");
    } else if (c.camera) {
      s.camera = c.camera;
      if (!c.frame_id.empty()) camera_info_frame_id_ = c.frame_id;
      if (c.lens_distortion && !distortion_logged_) {
        distortion_logged_ = true;
        *log_ << "jpcr dds: " << config_.camera_info_topic
              << ": the camera has lens distortion, which is not applied: the depth is used as"
                 " received and must be rectified (an image_rect topic), with the intrinsics of P"
              << std::endl;
      }
    } else {
      reject(config_.camera_info_topic, c.problem);
    }
  }
  s.take_waiting_depth(s.frames.size());
  log_camera_info_wait();
  log_keep_last_publishers();
  std::deque<ReceivedImage> images;
  std::size_t dropped = 0;
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    if (s.camera) {
      images.swap(s.images);
    } else {  // good images wait in the queue for a camera_info; bad ones go now
      for (auto it = s.images.begin(); it != s.images.end();) {
        if (it->problem.empty()) {
          ++it;
          continue;
        }
        images.push_back(std::move(*it));
        it = s.images.erase(it);
      }
    }
  }
  // The newest queue_depth good images are the ones the bound below keeps: older ones (and the
  // decoded frames waiting before them) are dropped now, without being decoded.
  std::size_t stale = 0, newer_good = 0;
  std::vector<char> keep(images.size(), 1);
  for (std::size_t k = images.size(); k-- > 0;)
    if (images[k].problem.empty() && ++newer_good > s.queue_depth) {
      keep[k] = 0;
      ++stale;
    }
  for (std::size_t k = 0; k < images.size(); ++k) {
    const ReceivedImage& r = images[k];
    if (!r.problem.empty()) {
      reject(config_.depth_topic, r.problem);
      continue;
    }
    if (!keep[k]) continue;
    if (!of_this_camera(r.frame_id)) {
      reject(config_.depth_topic, other_camera(r.frame_id));
      continue;
    }
    // Some drivers publish camera_info in another frame than the depth (aligned depth beside the
    // colour camera's info): the intrinsics are still the depth's, so it is said once, not
    // rejected.
    if (!r.frame_id.empty() && !camera_info_frame_id_.empty() &&
        camera_info_frame_id_ != r.frame_id && !frame_mismatch_logged_) {
      frame_mismatch_logged_ = true;
      *log_ << "jpcr dds: " << config_.camera_info_topic << " is in frame '"
            << camera_info_frame_id_ << "', the depth images in '" << r.frame_id
            << "'; the camera_info's intrinsics are used for the depth as they are" << std::endl;
    }
    try {
      s.frames.push_back(decode_depth_frame(r.image.view(), r.stamp, *s.camera, s.limits));
      s.frame_ids.push_back(r.frame_id);
      ++frames_;
    } catch (const InputError& e) {
      reject(config_.depth_topic, e.what());
    }
  }
  // Decoded frames wait for the caller under the same KEEP_LAST bound as the received images: a
  // caller slower than the camera gets the newest, the oldest go, counted.
  for (; s.frames.size() > s.queue_depth; ++stale) {
    s.frames.pop_front();
    s.frame_ids.pop_front();
  }
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    s.dropped += stale;
    dropped = s.dropped;
  }
  // Samples Cyclone itself knows it lost on the way (e.g. gone from the writer's history before
  // a retransmission): counted as dropped too.
  dds_sample_lost_status_t lost{};
  if (dds_get_sample_lost_status(s.depth.handle(), &lost) == DDS_RETCODE_OK &&
      lost.total_count > lost_) {
    *log_ << "jpcr dds: " << config_.depth_topic << ": " << lost.total_count - lost_
          << " frame(s) lost in transport, " << lost.total_count << " in all" << std::endl;
    lost_ = lost.total_count;
  }
  std::size_t left_out = 0;
  if (dropped > dropped_seen_ && drop_lines_.allow(left_out)) {
    *log_ << "jpcr dds: " << config_.depth_topic << ": dropped " << dropped - dropped_logged_
          << " frame(s), " << dropped << " in all: frames arrive faster than they are processed"
          << (s.camera ? "" : " or no camera_info received yet on " + config_.camera_info_topic)
          << " (keep last " << s.queue_depth << ")" << LogBudget::note(left_out) << std::endl;
    dropped_logged_ = dropped;
  }
  dropped_seen_ = dropped;
}

std::optional<Frame> DdsDepthSubscriber::wait_frame(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  State& s = *state_;
  // What process() would act on: a camera_info, a new drop, a bad image, or a good one that has
  // its camera.
  auto work = [&] {
    if (!s.cameras.empty() || s.dropped != dropped_seen_) return true;
    if (s.depth_incompatible != State::kNoPolicy || s.camera_incompatible != State::kNoPolicy)
      return true;
    if (s.camera) return !s.images.empty() || s.depth_pending;
    return std::any_of(s.images.begin(), s.images.end(),
                       [](const ReceivedImage& r) { return !r.problem.empty(); });
  };
  for (;;) {
    process();
    if (!s.frames.empty()) {
      Frame f = std::move(s.frames.front());
      s.frames.pop_front();
      frame_id_ = std::move(s.frame_ids.front());
      s.frame_ids.pop_front();
      return f;
    }
    std::unique_lock<std::mutex> lock(s.mutex);
    if (!s.arrived.wait_until(lock, deadline, work)) return std::nullopt;
  }
}

}  // namespace jpcr
