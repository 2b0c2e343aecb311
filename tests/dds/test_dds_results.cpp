// Real Cyclone DDS round trips on loopback for the published result topics: pose, odometry with
// covariance, path to a late joiner, a 640x480 32FC2 curvature map bit-exact, its colour image;
// the split deployment's keyframe messages.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "dds_test_config.hpp"
#include "jpcr/io/dds/dds_keyframe_link.hpp"
#include "jpcr/io/dds/dds_result_publisher.hpp"
#include "jpcr/io/dds/ros_messages.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

using std::chrono::milliseconds;
constexpr milliseconds kTimeout{5000};

// Waits for and takes one sample, converted by `convert` while the loan is valid.
template <typename Msg, typename Convert>
auto take_one(const DdsReader<Msg>& reader, Convert convert, milliseconds timeout = kTimeout)
    -> std::optional<decltype(convert(std::declval<const Msg&>()))> {
  std::optional<decltype(convert(std::declval<const Msg&>()))> out;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!out && std::chrono::steady_clock::now() < deadline) {
    reader.wait(milliseconds(100));
    reader.take([&](const Msg& m) {
      if (!out) out = convert(m);
    });
  }
  return out;
}

StampedPose some_pose(double t) {
  Vector6d xi;
  xi << 0.3, -1.2, 2.5, 0.1, -0.4, 0.9;
  return StampedPose{t, se3_exp(xi * (1.0 + t))};
}

void expect_same_pose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

class DdsResults : public ::testing::Test {
 protected:
  DdsConfig config_ =
      test::loopback_dds_config(::testing::UnitTest::GetInstance()->current_test_info()->name());
  DdsParticipant publisher_side_{config_};
  DdsParticipant subscriber_side_{config_};
  DdsResultPublisher publisher_{publisher_side_, config_};

  template <typename Msg>
  DdsReader<Msg> reader(ResultTopic topic) {
    return DdsReader<Msg>(subscriber_side_, result_topic_name(config_, topic),
                          result_topic_qos(config_, topic));
  }
};

TEST_F(DdsResults, TopicNamesAndQosFollowRosConventions) {
  EXPECT_EQ(result_topic_name(DdsConfig{}, ResultTopic::kOdometry), "rt/jpcr/odom");
  EXPECT_EQ(result_topic_name(DdsConfig{}, ResultTopic::kCurvatureColor),
            "rt/jpcr/curvature_color");
  EXPECT_EQ(result_topic_name(DdsConfig{}, ResultTopic::kCurvatureSd), "rt/jpcr/curvature_sd");
  const DdsQos sd = result_topic_qos(DdsConfig{}, ResultTopic::kCurvatureSd);
  EXPECT_TRUE(sd.reliable && sd.transient_local && sd.depth == DdsConfig{}.image_history_depth);
  const DdsQos path = result_topic_qos(DdsConfig{}, ResultTopic::kPath);
  EXPECT_TRUE(path.reliable && path.transient_local && path.depth == 1);
  DdsConfig deep;
  deep.history_depth = 7;
  const DdsQos increments = result_topic_qos(deep, ResultTopic::kPath, PathUpdates::kIncremental);
  EXPECT_TRUE(increments.reliable && increments.transient_local && increments.depth == 7);
  const DdsQos odom = result_topic_qos(DdsConfig{}, ResultTopic::kOdometry);
  EXPECT_TRUE(odom.reliable && odom.transient_local && odom.depth == DdsConfig{}.history_depth);
}

TEST_F(DdsResults, WaitsForReadersCountedOverTheTopics) {
  EXPECT_EQ(publisher_.matched_readers(), 0);
  EXPECT_FALSE(publisher_.wait_for_readers(1, milliseconds(50)));
  // keep_waiting saying no ends the wait at once, not at the timeout.
  int asked = 0;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(publisher_.wait_for_readers(1, kTimeout, [&] { return ++asked < 3; }));
  EXPECT_EQ(asked, 3);
  EXPECT_LT(std::chrono::steady_clock::now() - start, kTimeout / 5);
  // One reader per topic: each counts.
  auto odom = reader<RosOdometry>(ResultTopic::kOdometry);
  auto pose = reader<RosPoseStamped>(ResultTopic::kKeyframePose);
  auto path = reader<RosPath>(ResultTopic::kPath);
  auto curvature = reader<RosImage>(ResultTopic::kCurvature);
  auto color = reader<RosImage>(ResultTopic::kCurvatureColor);
  ASSERT_TRUE(publisher_.wait_for_readers(5, kTimeout));
  EXPECT_FALSE(publisher_.wait_for_readers(6, milliseconds(50)));
  auto sd = reader<RosImage>(ResultTopic::kCurvatureSd);
  ASSERT_TRUE(publisher_.wait_for_readers(6, kTimeout));
  for (const ResultTopic topic :
       {ResultTopic::kOdometry, ResultTopic::kKeyframePose, ResultTopic::kPath,
        ResultTopic::kCurvature, ResultTopic::kCurvatureColor, ResultTopic::kCurvatureSd})
    EXPECT_EQ(publisher_.matched(topic), 1) << to_string(topic);
  EXPECT_EQ(publisher_.matched_readers(), 6);
}

TEST_F(DdsResults, KeyframePoseArrives) {
  auto poses = reader<RosPoseStamped>(ResultTopic::kKeyframePose);
  ASSERT_TRUE(
      test::eventually([&] { return publisher_.matched(ResultTopic::kKeyframePose) == 1; }));
  const StampedPose sent = some_pose(1305031102.5);
  publisher_.publish_keyframe(sent, {}, {});
  const auto got = take_one(poses, [](const RosPoseStamped& m) {
    return std::make_pair(stamped_pose_of(m), std::string(m.header.frame_id));
  });
  ASSERT_TRUE(got);
  EXPECT_NEAR(got->first.timestamp, sent.timestamp, 1e-6);
  expect_same_pose(got->first.pose, sent.pose);
  EXPECT_EQ(got->second, "map");
}

TEST_F(DdsResults, OdometryCarriesTheCovariance) {
  auto odom = reader<RosOdometry>(ResultTopic::kOdometry);
  ASSERT_TRUE(test::eventually([&] { return publisher_.matched(ResultTopic::kOdometry) == 1; }));
  Matrix6d cov;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      cov(r, c) = r == c ? 1e-4 * (r + 1) : 1e-6 * (r + 1) * (c + 7);  // asymmetric: checks order
  const StampedPose sent = some_pose(2.25);
  publisher_.publish_odometry(sent, cov);
  struct Got {
    StampedPose pose;
    Matrix6d cov, twist_cov;
    std::string frame, child;
  };
  const auto got = take_one(odom, [](const RosOdometry& m) {
    return Got{StampedPose{to_seconds(stamp_of(m.header)), pose_of(m.pose.pose)},
               covariance_of(m.pose.covariance), covariance_of(m.twist.covariance),
               m.header.frame_id, m.child_frame_id};
  });
  ASSERT_TRUE(got);
  EXPECT_EQ(got->pose.timestamp, 2.25);
  expect_same_pose(got->pose.pose, sent.pose);
  EXPECT_EQ(got->cov, cov);
  EXPECT_EQ(got->twist_cov, -Matrix6d::Identity());
  EXPECT_EQ(got->frame, "map");
  EXPECT_EQ(got->child, "camera_depth_optical_frame");
}

TEST_F(DdsResults, LateJoinerReceivesTheLastPath) {
  Trajectory first = {some_pose(0.0), some_pose(0.1), some_pose(0.2)};
  Trajectory last = first;
  last.push_back(some_pose(0.3));
  last.push_back(some_pose(0.4));
  publisher_.publish_path(first);
  publisher_.publish_path(last);
  auto path = reader<RosPath>(ResultTopic::kPath);  // joins after both were published
  const auto got = take_one(path, [](const RosPath& m) { return trajectory_of(m); });
  ASSERT_TRUE(got);
  ASSERT_EQ(got->size(), 5u);
  for (std::size_t i = 0; i < last.size(); ++i) {
    EXPECT_NEAR((*got)[i].timestamp, last[i].timestamp, 1e-9);
    expect_same_pose((*got)[i].pose, last[i].pose);
  }
  // Depth 1: nothing older follows.
  EXPECT_EQ(path.take([](const RosPath&) {}), 0u);
}

// keep_history: false publishes each final pose in one path only: a reader with the topic's QoS
// must get every path published back to back, live or joining late (with a depth-1 path topic a
// late joiner got the last of 5 and a reader that fell behind lost the ones in between).
TEST_F(DdsResults, EveryIncrementalPathArrivesLiveAndToALateJoiner) {
  DdsResultPublisher increments(publisher_side_, config_, nullptr, PathUpdates::kIncremental);
  const DdsQos qos = result_topic_qos(config_, ResultTopic::kPath, PathUpdates::kIncremental);
  const std::string topic = result_topic_name(config_, ResultTopic::kPath);
  DdsReader<RosPath> live(subscriber_side_, topic, qos);
  ASSERT_TRUE(test::eventually([&] { return increments.matched(ResultTopic::kPath) == 1; }));
  constexpr int kPaths = 5;
  for (int i = 0; i < kPaths; ++i)
    increments.publish_path({some_pose(0.1 * i)});
  ASSERT_TRUE(increments.flush(kTimeout));
  DdsReader<RosPath> late(subscriber_side_, topic, qos);
  for (const DdsReader<RosPath>* reader : {&live, &late}) {
    std::vector<double> stamps;
    const auto deadline = std::chrono::steady_clock::now() + kTimeout;
    while (stamps.size() < kPaths && std::chrono::steady_clock::now() < deadline) {
      reader->wait(milliseconds(100));
      reader->take([&](const RosPath& m) {
        for (const StampedPose& p : trajectory_of(m))
          stamps.push_back(p.timestamp);
      });
    }
    ASSERT_EQ(stamps.size(), static_cast<std::size_t>(kPaths))
        << (reader == &late ? "late" : "live");
    for (int i = 0; i < kPaths; ++i)
      EXPECT_NEAR(stamps[i], 0.1 * i, 1e-9);
  }
}

// Every result topic keeps its last samples: a transient-local reader that joins after three
// keyframes (as one does that discovery let match late) gets the last image_history_depth maps
// and all three poses, oldest first; a volatile reader, ROS 2's default, matches and gets none.
TEST_F(DdsResults, LateTransientLocalReaderGetsTheKeptResults) {
  const Image<Eigen::Vector2f> k(32, 24, Eigen::Vector2f(0.5f, -2.0f));
  for (int i = 0; i < 3; ++i)
    publisher_.publish_keyframe(some_pose(1.0 + i), k, {}, Image<float>(32, 24, float(i)));
  auto poses = reader<RosPoseStamped>(ResultTopic::kKeyframePose);
  auto sd = reader<RosImage>(ResultTopic::kCurvatureSd);
  DdsQos volatile_qos = result_topic_qos(config_, ResultTopic::kCurvatureSd);
  volatile_qos.transient_local = false;
  DdsReader<RosImage> volatile_sd(
      subscriber_side_, result_topic_name(config_, ResultTopic::kCurvatureSd), volatile_qos);
  std::vector<double> pose_stamps;
  std::vector<float> sd_values;
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while ((pose_stamps.size() < 3 || sd_values.size() < 2) &&
         std::chrono::steady_clock::now() < deadline) {
    poses.wait(milliseconds(50));
    poses.take(
        [&](const RosPoseStamped& m) { pose_stamps.push_back(stamped_pose_of(m).timestamp); });
    sd.take([&](const RosImage& m) {
      sd_values.push_back(decode_curvature_sd_image(image_view_of(m), {})[0]);
    });
  }
  ASSERT_EQ(config_.image_history_depth, 2);
  EXPECT_EQ(pose_stamps, (std::vector<double>{1.0, 2.0, 3.0}));
  EXPECT_EQ(sd_values, (std::vector<float>{1.0f, 2.0f}));
  ASSERT_TRUE(test::eventually([&] { return publisher_.matched(ResultTopic::kCurvatureSd) == 2; }));
  EXPECT_EQ(volatile_sd.take([](const RosImage&) {}), 0u);
  publisher_.publish_keyframe(some_pose(4.0), k, {}, Image<float>(32, 24, 3.0f));
  EXPECT_TRUE(take_one(volatile_sd, [](const RosImage& m) { return m.header.stamp.sec; }) == 4);
}

TEST_F(DdsResults, CurvatureMap640x480ArrivesBitExact) {
  auto curvature = reader<RosImage>(ResultTopic::kCurvature);
  auto color = reader<RosImage>(ResultTopic::kCurvatureColor);
  ASSERT_TRUE(test::eventually([&] {
    return publisher_.matched(ResultTopic::kCurvature) == 1 &&
           publisher_.matched(ResultTopic::kCurvatureColor) == 1;
  }));
  std::mt19937 rng(5);
  std::normal_distribution<float> normal(0.0f, 3.0f);
  Image<Eigen::Vector2f> k(640, 480, Eigen::Vector2f::Zero());
  ColorImage c(640, 480);
  for (std::size_t i = 0; i < k.size(); ++i) {
    k[i] = i % 17 == 0 ? Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN())
                       : Eigen::Vector2f(normal(rng), normal(rng));
    c[i] = Rgb8{std::uint8_t(i), std::uint8_t(i >> 8), std::uint8_t(i >> 16)};
  }
  publisher_.publish_keyframe(some_pose(4.0), k, c);
  const auto got = take_one(curvature, [](const RosImage& m) {
    EXPECT_STREQ(m.encoding, "32FC2");
    EXPECT_EQ(m.step, 640u * 8u);
    EXPECT_STREQ(m.header.frame_id, "camera_depth_optical_frame");
    return decode_curvature_image(image_view_of(m), {});
  });
  ASSERT_TRUE(got);
  ASSERT_EQ(got->width(), 640);
  ASSERT_EQ(got->height(), 480);
  EXPECT_EQ(std::memcmp(got->data(), k.data(), k.size() * sizeof(Eigen::Vector2f)), 0);
  const auto got_color =
      take_one(color, [](const RosImage& m) { return decode_rgb8_image(image_view_of(m), {}); });
  ASSERT_TRUE(got_color);
  EXPECT_EQ(std::memcmp(got_color->data(), c.data(), c.size() * sizeof(Rgb8)), 0);
}

TEST_F(DdsResults, CurvatureSdArrivesBitExactWithTheMapsStamp) {
  auto sd_reader = reader<RosImage>(ResultTopic::kCurvatureSd);
  ASSERT_TRUE(test::eventually([&] { return publisher_.matched(ResultTopic::kCurvatureSd) == 1; }));
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> uniform(0.0f, 4.0f);
  const Image<Eigen::Vector2f> k(320, 240, Eigen::Vector2f(0.5f, -2.0f));
  Image<float> sd(320, 240, 0.0f);
  for (std::size_t i = 0; i < sd.size(); ++i)
    sd[i] = i % 13 == 0 ? std::numeric_limits<float>::quiet_NaN() : uniform(rng);
  // An sd map the size of another map is a caller's mistake, refused before anything is written.
  EXPECT_THROW(publisher_.publish_keyframe(some_pose(5.0), k, {}, Image<float>(32, 24, 1.0f)),
               std::invalid_argument);
  publisher_.publish_keyframe(some_pose(5.5), k, {}, sd);
  const auto got = take_one(sd_reader, [](const RosImage& m) {
    EXPECT_STREQ(m.encoding, "32FC1");
    EXPECT_EQ(m.header.stamp.sec, 5);
    EXPECT_EQ(m.header.stamp.nanosec, 500000000u);
    EXPECT_STREQ(m.header.frame_id, "camera_depth_optical_frame");
    return decode_curvature_sd_image(image_view_of(m), {});
  });
  ASSERT_TRUE(got);
  ASSERT_EQ(got->width(), 320);
  ASSERT_EQ(got->height(), 240);
  EXPECT_EQ(std::memcmp(got->data(), sd.data(), sd.size() * sizeof(float)), 0);
  // Without an sd map nothing goes out on the topic.
  publisher_.publish_keyframe(some_pose(6.0), k, {});
  EXPECT_FALSE(take_one(
      sd_reader, [](const RosImage&) { return 0; }, milliseconds(500)));
  EXPECT_EQ(publisher_.writes_failed(), 0u);
}

TEST_F(DdsResults, KeyframeMessageRoundTrips) {
  const std::string topic = config_.topic_prefix + "keyframe";
  DdsWriter<RosKeyframe> writer(publisher_side_, topic, DdsQos{});
  DdsReader<RosKeyframe> reader(subscriber_side_, topic, DdsQos{});
  ASSERT_TRUE(writer.wait_matched(1, kTimeout));
  Frame frame;
  frame.timestamp = 7.5;
  frame.camera = CameraIntrinsics{}.resized(32, 24);  // a real camera: principal point inside
  frame.depth = DepthImage(32, 24, 1.25f);
  frame.depth(3, 4) = 0.0f;
  Matrix6d cov = Matrix6d::Identity() * 1e-3;
  cov(0, 5) = cov(5, 0) = 2e-5;  // a covariance is symmetric
  const Trajectory tracked = {some_pose(6.5), some_pose(7.0)};
  const KeyframeMessage message(frame, some_pose(7.5), cov, DepthEncoding::kMetres32, "map", "cam",
                                9, tracked);
  writer.write(message.message());
  const auto got = take_one(reader, [](const RosKeyframe& m) { return decode_keyframe(m, {}); });
  ASSERT_TRUE(got);
  EXPECT_FALSE(got->end_of_stream);
  EXPECT_EQ(got->frame.timestamp, 7.5);
  EXPECT_EQ(got->frame.camera.fx, frame.camera.fx);
  EXPECT_EQ(got->frame.camera.width, 32);
  for (std::size_t i = 0; i < frame.depth.size(); ++i)
    ASSERT_EQ(got->frame.depth[i], frame.depth[i]);
  expect_same_pose(got->pose.pose, some_pose(7.5).pose);
  EXPECT_EQ(got->covariance, cov);
  EXPECT_EQ(got->frame_index, 9);
  EXPECT_EQ(got->camera_frame_id, "cam");  // the back end publishes in the camera's frame
  ASSERT_EQ(got->tracked.size(), 2u);
  EXPECT_EQ(got->tracked[1].timestamp, 7.0);
  expect_same_pose(got->tracked[1].pose, tracked[1].pose);

  // The end-of-stream marker: the frames after the last keyframe, no depth.
  const KeyframeMessage end(12, {some_pose(8.0)}, "map");
  writer.write(end.message());
  const auto last = take_one(reader, [](const RosKeyframe& m) { return decode_keyframe(m, {}); });
  ASSERT_TRUE(last);
  EXPECT_TRUE(last->end_of_stream);
  EXPECT_EQ(last->frame_index, 12);
  ASSERT_EQ(last->tracked.size(), 1u);
  EXPECT_EQ(last->tracked[0].timestamp, 8.0);
}

// A keyframe whose covariance or frame index could not have come from a front end is refused,
// naming the problem (decode only: no transport involved).
TEST(KeyframeDecode, ImpossibleCovarianceOrIndexIsRefused) {
  Frame frame;
  frame.timestamp = 3.0;
  frame.camera = CameraIntrinsics{}.resized(16, 12);
  frame.depth = DepthImage(16, 12, 2.0f);
  Matrix6d cov = Matrix6d::Identity() * 1e-4;
  cov(1, 2) = cov(2, 1) = 3e-6;
  const auto refusal = [&](const Matrix6d& c, std::uint32_t index = 4) -> std::string {
    const KeyframeMessage message(frame, some_pose(3.0), c, DepthEncoding::kMetres32, "map", "cam");
    RosKeyframe m = message.message();
    m.frame_index = index;
    try {
      decode_keyframe(m, {});
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(refusal(cov), "");
  EXPECT_EQ(refusal(Matrix6d::Zero()), "");  // the first frame's
  Matrix6d bad = cov;
  bad(0, 0) = std::nan("");
  EXPECT_EQ(refusal(bad), "keyframe covariance is not finite");
  bad = cov;
  bad(1, 2) = 4e-6;
  EXPECT_EQ(refusal(bad), "keyframe covariance is not symmetric");
  bad = cov;
  bad(5, 5) = -1e-4;
  EXPECT_EQ(refusal(bad), "keyframe covariance has a negative variance");
  EXPECT_EQ(refusal(cov, 3000000000u), "keyframe frame_index 3000000000 is out of range");
}

// The split deployment's link: keyframes arrive in order over the keep-all topic, a malformed
// one is rejected with one log line and reception goes on.
TEST_F(DdsResults, KeyframeLinkDeliversInOrderAndRejectsMalformedKeyframes) {
  std::ostringstream log;
  DdsKeyframeReader reader(subscriber_side_, config_, &log);
  const DdsKeyframeWriter writer(publisher_side_, config_);
  ASSERT_TRUE(writer.wait_matched(kTimeout));
  Frame frame;
  frame.camera = CameraIntrinsics{}.resized(16, 12);
  frame.depth = DepthImage(16, 12, 2.0f);
  for (int i = 0; i < 3; ++i) {
    frame.timestamp = 1.0 + i;
    writer.publish(frame, some_pose(frame.timestamp), Matrix6d::Identity(), 2 * i,
                   i == 0 ? Trajectory{} : Trajectory{some_pose(0.5 + i)});
  }
  // Data length != step x height.
  KeyframeMessage bad(frame, some_pose(4.0), Matrix6d::Identity(), DepthEncoding::kMetres32, "map",
                      "cam", 6);
  RosKeyframe shortened = bad.message();
  shortened.depth.data._length -= 4;
  const DdsWriter<RosKeyframe> raw(publisher_side_, keyframe_topic_name(config_),
                                   keyframe_topic_qos());
  ASSERT_TRUE(raw.wait_matched(1, kTimeout));
  raw.write(shortened);
  ASSERT_TRUE(raw.wait_for_acks(kTimeout));  // received before the end of stream is sent
  writer.publish_end(7, {some_pose(5.0)});
  std::vector<int> indices;
  bool end = false;
  while (!end) {
    const std::optional<DecodedKeyframe> k = reader.wait(kTimeout);
    ASSERT_TRUE(k) << "after " << indices.size() << " keyframes";
    end = k->end_of_stream;
    indices.push_back(k->frame_index);
  }
  EXPECT_EQ(indices, (std::vector<int>{0, 2, 4, 7}));
  EXPECT_EQ(reader.samples_rejected(), 1u);
  EXPECT_NE(log.str().find("keyframe: rejected sample: data is 764 bytes"), std::string::npos)
      << log.str();
}

// The back end's reader holds at most dds.keyframe_queue unread keyframes: a publish into a full
// queue waits (asking keep_waiting after each try of kKeyframeWriteTry ms), and once the back end
// takes them the same keyframe goes through; none is lost or reordered.
TEST_F(DdsResults, KeyframePublishWaitsWhileTheBackEndsQueueIsFull) {
  config_.keyframe_queue = 2;
  DdsKeyframeReader reader(subscriber_side_, config_);
  const DdsKeyframeWriter writer(publisher_side_, config_);
  ASSERT_TRUE(writer.wait_matched(kTimeout));
  Frame frame;
  frame.camera = CameraIntrinsics{}.resized(16, 12);
  frame.depth = DepthImage(16, 12, 2.0f);
  const auto publish = [&](int index, const KeepWaiting& keep_waiting) {
    frame.timestamp = 1.0 + index;
    return writer.publish(frame, some_pose(frame.timestamp), Matrix6d::Identity(), index, {},
                          keep_waiting);
  };
  std::vector<double> asked;
  const auto give_up = [&](double waited) {
    asked.push_back(waited);
    return false;
  };
  EXPECT_TRUE(publish(0, give_up));
  EXPECT_TRUE(publish(1, give_up));
  EXPECT_TRUE(asked.empty());
  EXPECT_FALSE(publish(2, give_up));  // the queue holds 0 and 1
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_GE(asked[0], 0.9 * kKeyframeWriteTry / 1000.0);  // after one try
  std::vector<int> indices;
  for (int i = 0; i < 2; ++i) {
    const std::optional<DecodedKeyframe> k = reader.wait(kTimeout);
    ASSERT_TRUE(k);
    indices.push_back(k->frame_index);
  }
  EXPECT_TRUE(publish(2, give_up));
  const std::optional<DecodedKeyframe> k = reader.wait(kTimeout);
  ASSERT_TRUE(k);
  indices.push_back(k->frame_index);
  EXPECT_EQ(indices, (std::vector<int>{0, 1, 2}));
  EXPECT_FALSE(reader.wait(milliseconds(200)));  // nothing twice
}

// A sample Cyclone refuses (a 320x240 32FC2 map, 614 kB, above a MaxSampleSize of 300 kB) is
// counted and logged, and publishing goes on: jpcr_node exited mid-run on the first one.
TEST(DdsResultPublisher, ARefusedSampleIsCountedAndPublishingGoesOn) {
  DdsConfig config = test::loopback_dds_config("refused");
  config.domain_id = 201 + static_cast<int>(::getpid() % 30);  // a domain of its own settings
  config.cyclone_uri =
      "<CycloneDDS><Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
      "<AllowMulticast>false</AllowMulticast></General><Discovery><Peers><Peer "
      "address=\"127.0.0.1\"/></Peers></Discovery><Internal><MaxSampleSize>300kB</MaxSampleSize>"
      "</Internal></Domain></CycloneDDS>";
  DdsParticipant side{config};
  std::ostringstream log;
  DdsResultPublisher publisher(side, config, &log);
  DdsReader<RosOdometry> odometry(side, result_topic_name(config, ResultTopic::kOdometry),
                                  result_topic_qos(config, ResultTopic::kOdometry));
  DdsReader<RosImage> curvature(side, result_topic_name(config, ResultTopic::kCurvature),
                                result_topic_qos(config, ResultTopic::kCurvature));
  ASSERT_TRUE(test::eventually([&] { return publisher.matched(ResultTopic::kCurvature) > 0; }));
  const Image<Eigen::Vector2f> k(320, 240, Eigen::Vector2f(1.0f, -1.0f));
  EXPECT_NO_THROW(publisher.publish_keyframe(some_pose(1.0), k, ColorImage()));
  EXPECT_EQ(publisher.writes_failed(), 1u) << log.str();
  EXPECT_NE(log.str().find("curvature"), std::string::npos) << log.str();
  publisher.publish_odometry(some_pose(2.0), Matrix6d::Identity());
  EXPECT_EQ(publisher.writes_failed(), 1u);
  const auto got = take_one(odometry, [](const RosOdometry& m) { return stamp_of(m.header); });
  ASSERT_TRUE(got);
  EXPECT_EQ(got->sec, 2);
}

TEST(DdsParticipant, BadDomainIdIsAnError) {
  EXPECT_THROW(DdsParticipant(233), DdsError);
  EXPECT_THROW(DdsParticipant(-1), DdsError);
}

}  // namespace
}  // namespace jpcr
