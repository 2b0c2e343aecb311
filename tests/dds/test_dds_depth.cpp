// Depth input over real Cyclone DDS on loopback: a frame published as 16UC1 or 32FC1 with its
// camera_info arrives as the identical jpcr::Frame; malformed samples are rejected with one log
// line each while the subscriber keeps receiving; frames the caller is too slow for are dropped,
// counted and logged.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <sstream>
#include <thread>
#include <vector>

#include "dds_test_config.hpp"
#include "jpcr/io/dds/dds_depth_publisher.hpp"
#include "jpcr/io/dds/dds_depth_subscriber.hpp"
#include "jpcr/io/dds/dds_endpoint.hpp"
#include "jpcr/io/dds/dds_result_publisher.hpp"
#include "jpcr/io/dds/ros_messages.hpp"

namespace jpcr {
namespace {

using std::chrono::milliseconds;
constexpr milliseconds kTimeout{5000};

Frame test_frame(double timestamp) {
  Frame f;
  f.timestamp = timestamp;
  f.camera.fx = 520.5;
  f.camera.fy = 519.25;
  f.camera.cx = 160.5;
  f.camera.cy = 120.25;
  f.camera.width = 320;
  f.camera.height = 240;
  f.camera.distortion = {0.01, -0.02, 0.0, 0.0, 0.003};
  f.depth = DepthImage(320, 240);
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u)
      f.depth(u, v) = (u * v) % 13 == 0 ? 0.0f : 0.001f * static_cast<float>(400 + u + 7 * v);
  return f;
}

void expect_same_frame(const Frame& got, const Frame& sent, double depth_scale) {
  EXPECT_NEAR(got.timestamp, sent.timestamp, 1e-9);
  EXPECT_EQ(got.camera.fx, sent.camera.fx);
  EXPECT_EQ(got.camera.fy, sent.camera.fy);
  EXPECT_EQ(got.camera.cx, sent.camera.cx);
  EXPECT_EQ(got.camera.cy, sent.camera.cy);
  EXPECT_EQ(got.camera.width, sent.camera.width);
  EXPECT_EQ(got.camera.height, sent.camera.height);
  EXPECT_EQ(got.camera.distortion, sent.camera.distortion);
  EXPECT_EQ(got.camera.depth_scale, depth_scale);
  ASSERT_EQ(got.depth.width(), sent.depth.width());
  ASSERT_EQ(got.depth.height(), sent.depth.height());
  for (std::size_t i = 0; i < sent.depth.size(); ++i)
    ASSERT_EQ(got.depth[i], sent.depth[i]) << "pixel " << i;
}

class DdsDepth : public ::testing::Test {
 protected:
  DdsConfig config_ =
      test::loopback_dds_config(::testing::UnitTest::GetInstance()->current_test_info()->name());
  DdsParticipant camera_side_{config_};
  DdsParticipant node_side_{config_};
};

TEST_F(DdsDepth, FrameArrivesIdenticalIn16UC1And32FC1) {
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  for (const DepthEncoding encoding : {DepthEncoding::kMillimetres16, DepthEncoding::kMetres32}) {
    DdsDepthPublisher publisher(camera_side_, config_, encoding);
    ASSERT_TRUE(publisher.wait_for_subscribers(1, kTimeout));
    const Frame sent = test_frame(encoding == DepthEncoding::kMetres32 ? 10.5 : 3.125);
    publisher.publish(sent);
    const std::optional<Frame> got = subscriber.wait_frame(kTimeout);
    ASSERT_TRUE(got) << to_string(encoding);
    expect_same_frame(*got, sent, encoding == DepthEncoding::kMetres32 ? 1.0 : 1000.0);
  }
  EXPECT_EQ(subscriber.frames_received(), 2u);
  EXPECT_EQ(subscriber.samples_rejected(), 0u);
  // The camera has lens distortion: one line, once, says that it is not applied.
  EXPECT_EQ(log.str(), "jpcr dds: " + config_.camera_info_topic +
                           ": the camera has lens distortion, which is not applied: the depth is "
                           "used as received and must be rectified (an image_rect topic), "
                           "with the intrinsics of P\n");
}

// A camera's stamp of today (1.7e9 s) with nanoseconds a double cannot hold: the odometry jpcr
// publishes for that frame carries the same stamp, to the nanosecond, as ROS's exact-time sync
// and tf lookups at the image's stamp need (rounding the double gave 1733400000.000000000).
TEST_F(DdsDepth, ResultsForAFrameCarryItsStampToTheNanosecond) {
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  const DdsWriter<RosCameraInfoMsg> info_writer(camera_side_, config_.camera_info_topic,
                                                config_.camera_info_qos());
  const DdsWriter<RosImage> depth_writer(camera_side_, config_.depth_topic, config_.depth_qos());
  ASSERT_TRUE(depth_writer.wait_matched(1, kTimeout) && info_writer.wait_matched(1, kTimeout));
  Frame sent = test_frame(0.0);
  sent.camera.distortion = {};
  const RosStamp stamp{1733400000, 1};
  // The messages borrow their strings and data from these.
  const RosCameraInfo info_values = encode_camera_info(sent.camera);
  const RosImageBuffer depth_values = encode_depth_image(sent.depth, DepthEncoding::kMetres32);
  RosCameraInfoMsg info = camera_info_message(info_values, 0.0, config_.camera_frame_id);
  RosImage depth = image_message(depth_values, 0.0, config_.camera_frame_id);
  info.header.stamp = {stamp.sec, stamp.nanosec};
  depth.header.stamp = {stamp.sec, stamp.nanosec};
  info_writer.write(info);
  depth_writer.write(depth);
  const std::optional<Frame> got = subscriber.wait_frame(kTimeout);
  ASSERT_TRUE(got);

  DdsResultPublisher results(node_side_, config_);
  const DdsReader<RosOdometry> odometry(camera_side_,
                                        result_topic_name(config_, ResultTopic::kOdometry),
                                        result_topic_qos(config_, ResultTopic::kOdometry));
  ASSERT_TRUE(odometry.wait_matched(1, kTimeout));
  results.publish_odometry(StampedPose{got->timestamp, Eigen::Isometry3d::Identity()},
                           Matrix6d::Identity());
  std::optional<RosStamp> echoed;
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (!echoed && std::chrono::steady_clock::now() < deadline) {
    odometry.wait(milliseconds(100));
    odometry.take([&](const RosOdometry& m) { echoed = stamp_of(m.header); });
  }
  ASSERT_TRUE(echoed);
  EXPECT_EQ(echoed->sec, stamp.sec);
  EXPECT_EQ(echoed->nanosec, stamp.nanosec);
}

TEST_F(DdsDepth, WaitFrameTimesOutWithoutPublisher) {
  DdsDepthSubscriber subscriber(node_side_, config_);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(subscriber.wait_frame(milliseconds(200)));
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, milliseconds(190));
  EXPECT_LT(waited, milliseconds(2000));
}

TEST_F(DdsDepth, MalformedSamplesAreRejectedAndReceptionGoesOn) {
  config_.image_history_depth = 16;  // every sample of the burst is kept for the subscriber
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  DdsWriter<RosImage> images(camera_side_, config_.depth_topic, config_.depth_qos());
  DdsWriter<RosCameraInfoMsg> infos(camera_side_, config_.camera_info_topic,
                                    config_.camera_info_qos());
  ASSERT_TRUE(images.wait_matched(1, kTimeout));
  ASSERT_TRUE(infos.wait_matched(1, kTimeout));

  const Frame good = test_frame(1.0);
  const RosCameraInfo info = encode_camera_info(good.camera);
  const std::string frame_id = "cam";
  infos.write(camera_info_message(info, 1.0, frame_id));
  // Let the camera_info land first (a depth image before it would wait for it, checked the same).
  EXPECT_FALSE(subscriber.wait_frame(milliseconds(200)));

  const RosImageBuffer depth = encode_depth_image(good.depth, DepthEncoding::kMillimetres16);
  auto send_bad = [&](auto&& mutate) {
    RosImageBuffer b = depth;
    RosImage m = image_message(b, 1.0, frame_id);
    mutate(m, b);
    images.write(m);
  };
  send_bad([](RosImage& m, RosImageBuffer&) { m.data._length -= 2; });  // length
  send_bad([](RosImage& m, RosImageBuffer&) { m.encoding = const_cast<char*>("yuv422"); });
  send_bad([](RosImage& m, RosImageBuffer&) {
    m.width = m.height = 0;
    m.data._length = 0;
  });
  send_bad([](RosImage& m, RosImageBuffer&) {  // claims 100 MB
    m.height = 5000;
    m.width = 10000;
    m.step = 20000;
  });
  send_bad([](RosImage& m, RosImageBuffer&) { m.is_bigendian = 1; });
  send_bad([](RosImage& m, RosImageBuffer&) { m.step = 10; });
  RosCameraInfo bad_info = info;
  bad_info.p[0] = 0.0;
  infos.write(camera_info_message(bad_info, 1.0, frame_id));
  // A camera_info in another frame than the first camera_info's is a second camera's.
  infos.write(camera_info_message(info, 1.0, "colour_frame"));
  const Frame next = test_frame(2.0);
  const RosImageBuffer next_depth = encode_depth_image(next.depth, DepthEncoding::kMillimetres16);
  images.write(image_message(next_depth, 2.0, frame_id));

  const std::optional<Frame> got = subscriber.wait_frame(kTimeout);
  ASSERT_TRUE(got);
  expect_same_frame(*got, next, 1000.0);
  {  // a well-formed image of another camera, once the stream's frame is 'cam'
    RosImageBuffer b = depth;
    images.write(image_message(b, 3.0, "other_cam"));
  }
  EXPECT_FALSE(subscriber.wait_frame(milliseconds(500)));
  EXPECT_EQ(subscriber.samples_rejected(), 9u) << log.str();
  EXPECT_EQ(subscriber.frames_received(), 1u);
  const std::string text = log.str();
  // One line per rejected sample, and one (once) that the camera's lens distortion is not applied.
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10) << text;
  for (const char* expected :
       {"camera_info: the camera has lens distortion, which is not applied",
        "image_raw: rejected sample: data is 153598 bytes, step x height = 153600",
        "image_raw: rejected sample: unknown encoding 'yuv422'", "zero size 0x0",
        "claimed size step x height = 100000000 bytes exceeds the limit of 67108864",
        "big-endian data is not supported", "step 10 < width x 2 bytes = 640",
        "camera_info: rejected sample: camera_info P focal lengths fx = 0.000000",
        "image_raw: rejected sample: header.frame_id 'other_cam' is not the stream's 'cam'",
        "camera_info: rejected sample: header.frame_id 'colour_frame' is not the stream's "
        "camera_info frame 'cam'"}) {
    EXPECT_NE(text.find(expected), std::string::npos) << expected << "\nin:\n" << text;
  }
}

TEST_F(DdsDepth, DepthBeforeCameraInfoWaitsForIt) {
  DdsDepthSubscriber subscriber(node_side_, config_);
  DdsWriter<RosImage> images(camera_side_, config_.depth_topic, config_.depth_qos());
  DdsWriter<RosCameraInfoMsg> infos(camera_side_, config_.camera_info_topic,
                                    config_.camera_info_qos());
  ASSERT_TRUE(images.wait_matched(1, kTimeout) && infos.wait_matched(1, kTimeout));
  const Frame sent = test_frame(5.0);
  const RosImageBuffer depth = encode_depth_image(sent.depth, DepthEncoding::kMetres32);
  const std::string frame_id = "cam";
  images.write(image_message(depth, 5.0, frame_id));
  EXPECT_FALSE(subscriber.wait_frame(milliseconds(100)));
  const RosCameraInfo info = encode_camera_info(sent.camera);
  infos.write(camera_info_message(info, 5.0, frame_id));
  const std::optional<Frame> got = subscriber.wait_frame(kTimeout);
  ASSERT_TRUE(got);
  expect_same_frame(*got, sent, 1.0);
}

// Aligned depth beside the colour camera's camera_info (realsense-ros, xarm_ros2): the frames are
// used, with one line that names both frames.
TEST_F(DdsDepth, ACameraInfoInAnotherFrameThanTheDepthIsUsedAndSaidOnce) {
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  DdsWriter<RosImage> images(camera_side_, config_.depth_topic, config_.depth_qos());
  DdsWriter<RosCameraInfoMsg> infos(camera_side_, config_.camera_info_topic,
                                    config_.camera_info_qos());
  ASSERT_TRUE(images.wait_matched(1, kTimeout) && infos.wait_matched(1, kTimeout));
  for (const double t : {5.0, 6.0}) {
    const Frame sent = test_frame(t);
    infos.write(camera_info_message(encode_camera_info(sent.camera), t, "colour_frame"));
    EXPECT_FALSE(subscriber.wait_frame(milliseconds(100)));  // the camera_info lands first
    const RosImageBuffer depth = encode_depth_image(sent.depth, DepthEncoding::kMetres32);
    images.write(image_message(depth, t, "depth_frame"));
    const std::optional<Frame> got = subscriber.wait_frame(kTimeout);
    ASSERT_TRUE(got) << log.str();
    expect_same_frame(*got, sent, 1.0);
    EXPECT_EQ(subscriber.frame_id(), "depth_frame");
  }
  EXPECT_EQ(subscriber.samples_rejected(), 0u) << log.str();
  const std::string text = log.str();
  EXPECT_NE(text.find("is in frame 'colour_frame', the depth images in 'depth_frame'"),
            std::string::npos)
      << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;  // that line, and D's
}

// A best-effort camera (ROS sensor-data QoS) cannot match the reliable default: Cyclone delivers
// nothing, so the subscriber must say why and what to set.
TEST_F(DdsDepth, ABestEffortCameraIsNamedWithTheSettingThatMatchesIt) {
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  const DdsWriter<RosImage> images(camera_side_, config_.depth_topic, DdsQos{false, false, 2});
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (log.str().empty() && std::chrono::steady_clock::now() < deadline)
    subscriber.wait_frame(milliseconds(100));
  EXPECT_EQ(log.str(), "jpcr dds: " + config_.depth_topic +
                           ": a publisher offers a QoS this reader cannot match, its reliability: "
                           "a best-effort publisher (a ROS sensor-data camera) needs dds: "
                           "{input_reliability: best_effort}; its samples do not arrive\n");
  EXPECT_EQ(subscriber.matched(), 0);
}

// A publisher of nothing but bad samples (a misconfigured camera) must not flood the log: every
// sample is counted, the first 10 get a line each, the rest are left out until 10 s passed.
TEST_F(DdsDepth, AFloodOfBadSamplesIsCountedButLoggedInPart) {
  config_.image_history_depth = 64;  // every sample of the burst is kept for the subscriber
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  DdsWriter<RosImage> images(camera_side_, config_.depth_topic, config_.depth_qos());
  ASSERT_TRUE(images.wait_matched(1, kTimeout));
  RosImageBuffer rgb;
  rgb.width = 4;
  rgb.height = 2;
  rgb.encoding = "rgb8";
  rgb.step = 12;
  rgb.data.assign(24, 0);
  constexpr int kSent = 30;
  for (int i = 0; i < kSent; ++i)
    images.write(image_message(rgb, 1.0 + i, "cam"));
  ASSERT_TRUE(images.wait_for_acks(kTimeout));
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (subscriber.samples_rejected() < std::size_t{kSent} &&
         std::chrono::steady_clock::now() < deadline)
    subscriber.wait_frame(milliseconds(100));
  EXPECT_EQ(subscriber.samples_rejected(), std::size_t{kSent});
  const std::string text = log.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10) << text;
}

// Publishes `count` frames stamped first, first + 1, …, each acknowledged (it reached the
// subscriber's process), then gives the subscriber's listener time to queue them.
void publish_acknowledged(DdsDepthPublisher& publisher, double first, int count) {
  for (int i = 0; i < count; ++i) {
    publisher.publish(test_frame(first + i));
    ASSERT_TRUE(publisher.flush(kTimeout));
  }
  std::this_thread::sleep_for(milliseconds(200));
}

// The stamps of every frame the subscriber still has for its caller.
std::vector<double> drain(DdsDepthSubscriber& subscriber) {
  std::vector<double> stamps;
  while (const std::optional<Frame> f = subscriber.wait_frame(milliseconds(300)))
    stamps.push_back(f->timestamp);
  return stamps;
}

// A caller slower than the camera: of 7 frames sent before it asks, the queue (keep last 2)
// keeps the newest 2; the other 5 are counted and logged, not lost silently in Cyclone. The same
// with a KEEP_ALL camera (dds.input_history: keep_all on its side only): a keep-last caller does
// not hold it back.
TEST_F(DdsDepth, FramesTheCallerIsTooSlowForAreDroppedCountedAndLogged) {
  ASSERT_EQ(config_.image_history_depth, 2);
  for (const bool camera_keeps_all : {false, true}) {
    DdsConfig camera_config = config_;
    camera_config.input_keep_all = camera_keeps_all;
    std::ostringstream log;
    DdsDepthSubscriber subscriber(node_side_, config_, &log);
    DdsDepthPublisher publisher(camera_side_, camera_config, DepthEncoding::kMetres32);
    ASSERT_TRUE(publisher.wait_for_subscribers(1, kTimeout));
    publish_acknowledged(publisher, 1.0, 7);
    EXPECT_EQ(drain(subscriber), (std::vector<double>{6.0, 7.0}));
    EXPECT_EQ(subscriber.frames_dropped(), 5u);
    EXPECT_EQ(subscriber.frames_received(), 2u);
    EXPECT_NE(log.str().find("image_raw: dropped 5 frame(s), 5 in all"), std::string::npos)
        << log.str();
  }
}

// A caller that takes one frame for every two the camera sends: the frames waiting for it stay
// within the queue's bound (keep last 2) instead of piling up, and each frame is either
// returned or counted as dropped.
TEST_F(DdsDepth, FramesWaitingForASlowCallerStayWithinTheQueue) {
  ASSERT_EQ(config_.image_history_depth, 2);
  std::ostringstream log;
  DdsDepthSubscriber subscriber(node_side_, config_, &log);
  DdsDepthPublisher publisher(camera_side_, config_, DepthEncoding::kMetres32);
  ASSERT_TRUE(publisher.wait_for_subscribers(1, kTimeout));
  constexpr int kRounds = 5;
  std::vector<double> stamps;
  for (int round = 0; round < kRounds; ++round) {
    publish_acknowledged(publisher, 1.0 + 2 * round, 2);
    const std::optional<Frame> f = subscriber.wait_frame(milliseconds(300));
    ASSERT_TRUE(f.has_value()) << "round " << round;
    stamps.push_back(f->timestamp);
  }
  EXPECT_LE(subscriber.frames_waiting(), 2u);
  const std::vector<double> left = drain(subscriber);
  EXPECT_LE(left.size(), 2u);  // without the bound: 5
  EXPECT_EQ(stamps.size() + left.size() + subscriber.frames_dropped(), std::size_t{2 * kRounds});
  EXPECT_EQ(subscriber.frames_waiting(), 0u);
  ASSERT_FALSE(left.empty());
  EXPECT_DOUBLE_EQ(left.back(), 2.0 * kRounds) << "the oldest go, the newest stays";
}

// A keep_all caller cannot hold a KEEP_LAST camera back, and the frames that camera loses are
// not reported by Cyclone: the subscriber says so once the camera matches, and not for a
// KEEP_ALL one.
TEST_F(DdsDepth, AKeepAllCallerNamesAKeepLastCamera) {
  DdsConfig node_config = config_;
  node_config.input_keep_all = true;
  for (const bool camera_keeps_all : {true, false}) {
    DdsConfig camera_config = config_;
    camera_config.input_keep_all = camera_keeps_all;
    std::ostringstream log;
    DdsDepthSubscriber subscriber(node_side_, node_config, &log);
    DdsDepthPublisher publisher(camera_side_, camera_config, DepthEncoding::kMetres32);
    ASSERT_TRUE(publisher.wait_for_subscribers(1, kTimeout));
    ASSERT_TRUE(test::eventually([&] { return subscriber.matched() == 1; }));
    publisher.publish(test_frame(1.0));
    ASSERT_TRUE(subscriber.wait_frame(kTimeout).has_value());
    EXPECT_EQ(log.str().find("KEEP_LAST") != std::string::npos, !camera_keeps_all) << log.str();
  }
}

// dds.input_history: keep_all on both sides (a reader's resource limit of image_history_depth = 2
// images): the subscriber and the camera, matched.
class DdsDepthKeepAll : public DdsDepth {
 protected:
  static const DdsConfig& keeping_all(DdsConfig& config) {
    config.input_keep_all = true;
    return config;
  }
  void SetUp() override {
    ASSERT_EQ(config_.image_history_depth, 2);
    ASSERT_TRUE(publisher_.wait_for_subscribers(1, kTimeout));
  }
  std::ostringstream log_;
  DdsDepthSubscriber subscriber_{node_side_, keeping_all(config_), &log_};
  DdsDepthPublisher publisher_{camera_side_, config_, DepthEncoding::kMetres32};
};

// With dds.input_history: keep_all the images wait in the reader until the caller asks for a
// frame: they are frames waiting too (a stop reports them as left unprocessed), and they are
// counted without being taken.
TEST_F(DdsDepthKeepAll, FramesWaitingCountsTheImagesTheReaderStillHolds) {
  publish_acknowledged(publisher_, 1.0, 2);
  EXPECT_EQ(subscriber_.frames_waiting(), 2u);  // without the reader's count: 0
  EXPECT_EQ(subscriber_.frames_waiting(), 2u) << "counting takes nothing";
  EXPECT_EQ(drain(subscriber_), (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(subscriber_.frames_waiting(), 0u);
  EXPECT_EQ(subscriber_.frames_dropped(), 0u) << log_.str();
}

// A camera publishing as fast as it can to a caller that takes a frame every 30 ms waits for it,
// and every frame arrives, in order, none dropped.
TEST_F(DdsDepthKeepAll, ACameraWaitsForASlowCallerAndNothingIsDropped) {
  constexpr int kFrames = 12;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::atomic<int> written{0};
  std::thread camera([&] {
    for (int i = 0; i < kFrames; ++i) {
      if (!publisher_.publish(test_frame(1.0 + i),
                              [&] { return std::chrono::steady_clock::now() < give_up; }))
        return;
      ++written;
    }
  });
  std::vector<double> stamps;
  while (stamps.size() < std::size_t{kFrames} && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(milliseconds(30));  // the node at work
    if (const std::optional<Frame> f = subscriber_.wait_frame(milliseconds(500)))
      stamps.push_back(f->timestamp);
    // Held back, not queued without bound: at most the writer's 2 unacknowledged images, the
    // reader's 2 and the subscriber's 2 (unlimited, the camera ran 11 ahead at once).
    EXPECT_LE(written - static_cast<int>(stamps.size()), 6);
  }
  camera.join();
  EXPECT_EQ(written.load(), kFrames);
  std::vector<double> expected;
  for (int i = 0; i < kFrames; ++i)
    expected.push_back(1.0 + i);
  EXPECT_EQ(stamps, expected);
  EXPECT_EQ(subscriber_.frames_dropped(), 0u) << log_.str();
  EXPECT_EQ(subscriber_.frames_received(), std::size_t{kFrames});
  EXPECT_EQ(log_.str().find("dropped"), std::string::npos) << log_.str();
}

}  // namespace
}  // namespace jpcr
