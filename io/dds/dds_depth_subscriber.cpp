#include "jpcr/io/dds/dds_depth_subscriber.hpp"

#include <algorithm>
#include <deque>
#include <iostream>

#include "jpcr/io/dds/ros_messages.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// A depth image received before any camera_info, kept (copied) until one arrives.
struct PendingImage {
  RosImageBuffer image;
  RosStamp stamp;
};

}  // namespace

struct DdsDepthSubscriber::State {
  State(const DdsParticipant& p, const DdsConfig& c)
      : depth(p, c.depth_topic, c.depth_qos()),
        camera_info(p, c.camera_info_topic, c.camera_info_qos()) {
    limits.max_bytes = c.max_image_bytes();
    limits.max_side = static_cast<std::uint32_t>(c.max_image_side);
  }
  DdsReader<RosImage> depth;
  DdsReader<RosCameraInfoMsg> camera_info;
  RosImageLimits limits;
  std::optional<CameraIntrinsics> camera;
  std::deque<PendingImage> pending;
  std::deque<Frame> frames;
};

DdsDepthSubscriber::DdsDepthSubscriber(const DdsParticipant& participant, const DdsConfig& config,
                                       std::ostream* log)
    : config_(config),
      log_(log ? log : &std::cerr),
      state_(std::make_unique<State>(participant, config)) {}

DdsDepthSubscriber::~DdsDepthSubscriber() = default;

int DdsDepthSubscriber::matched() const {
  return state_->depth.matched();
}

void DdsDepthSubscriber::reject(const std::string& topic, const std::string& problem) {
  ++rejected_;
  *log_ << "jpcr dds: " << topic << ": rejected sample: " << problem << std::endl;
}

void DdsDepthSubscriber::poll() {
  State& s = *state_;
  s.camera_info.take([&](const RosCameraInfoMsg& m) {
    try {
      s.camera = decode_camera_info(camera_info_of(m), s.limits);
    } catch (const InputError& e) {
      reject(config_.camera_info_topic, e.what());
    }
  });
  auto decode = [&](const RosImageView& view, const RosStamp& stamp) {
    try {
      s.frames.push_back(decode_depth_frame(view, stamp, *s.camera, s.limits));
      ++frames_;
    } catch (const InputError& e) {
      reject(config_.depth_topic, e.what());
    }
  };
  if (s.camera) {
    for (const PendingImage& p : s.pending)
      decode(p.image.view(), p.stamp);
    s.pending.clear();
  }
  s.depth.take([&](const RosImage& m) {
    const RosImageView view = image_view_of(m);
    const RosStamp stamp = stamp_of(m.header);
    if (s.camera) return decode(view, stamp);
    try {  // keep a checked copy until a camera_info arrives
      check_image_layout(view, {{"16UC1", 2}, {"32FC1", 4}}, s.limits);
    } catch (const InputError& e) {
      return reject(config_.depth_topic, e.what());
    }
    if (s.pending.size() >= static_cast<std::size_t>(config_.image_history_depth)) {
      s.pending.pop_front();
      reject(config_.depth_topic, "no camera_info received yet on " + config_.camera_info_topic);
    }
    PendingImage p;
    p.image.height = view.height;
    p.image.width = view.width;
    p.image.encoding = std::string(view.encoding);
    p.image.step = view.step;
    p.image.data.assign(view.data, view.data + view.size);
    p.stamp = stamp;
    s.pending.push_back(std::move(p));
  });
}

std::optional<Frame> DdsDepthSubscriber::wait_frame(std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point deadline = Clock::now() + timeout;
  State& s = *state_;
  for (;;) {
    poll();
    if (!s.frames.empty()) {
      Frame f = std::move(s.frames.front());
      s.frames.pop_front();
      return f;
    }
    const Clock::time_point now = Clock::now();
    if (now >= deadline) return std::nullopt;
    const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - now);
    // Without a camera, a pending image waits for camera_info; otherwise depth is what we need.
    if (s.pending.empty()) {
      s.depth.wait(left);
    } else {
      s.camera_info.wait(left);
    }
  }
}

}  // namespace jpcr
