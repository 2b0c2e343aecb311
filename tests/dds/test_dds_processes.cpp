// Round trips between processes over the loopback interface (no in-process shortcut):
//   - jpcr_dds_play publishes the TUM test sequence as 32FC1; the frames received here equal
//     the frames read from the files;
//   - a 640x480 32FC2 map goes to a relay process (this binary run with --relay) and back
//     bit-exact.
// This file has the test binary's main(): with --relay it relays instead of running tests.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "dds_test_config.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/dds/dds_depth_subscriber.hpp"
#include "jpcr/io/dds/dds_result_publisher.hpp"
#include "jpcr/io/dds/ros_messages.hpp"
#include "jpcr/io/open_dataset.hpp"

extern char** environ;

namespace jpcr {
namespace {

using std::chrono::milliseconds;
const std::string kTumDir = std::string(JPCR_TEST_DATA_DIR) + "/tum_fr1_xyz_20";
const std::string kFr1 = std::string(JPCR_SOURCE_DIR) + "/configs/tum_fr1.yaml";

// A child process, killed and reaped on destruction unless it ended; stdout optionally to a file.
class Child {
 public:
  explicit Child(const std::vector<std::string>& argv, const std::string& stdout_file = "") {
    std::vector<char*> args;
    for (const std::string& a : argv)
      args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!stdout_file.empty()) {
      posix_spawn_file_actions_addopen(&actions, 1, stdout_file.c_str(),
                                       O_WRONLY | O_CREAT | O_TRUNC, 0644);
    }
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    wait();
  }
  bool started() const { return pid_ > 0; }
  // The exit status, waiting up to `timeout`; -1 when it is still running.
  int wait(milliseconds timeout = milliseconds(10000)) {
    int status = 0;
    const bool done =
        test::eventually([&] { return waitpid(pid_, &status, WNOHANG) == pid_; }, timeout);
    if (!done) return -1;
    pid_ = 0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
};

TEST(DdsProcesses, PlayedTumFramesArriveIdentical) {
  const std::string play = std::string(JPCR_BINARY_DIR) + "/tools/jpcr_dds_play";
  if (!std::filesystem::exists(play)) GTEST_SKIP() << play << " not built";
  DdsConfig config = test::loopback_dds_config("play");
  config.image_history_depth = 32;  // every frame is kept until taken
  const DdsParticipant participant(config);
  DdsDepthSubscriber subscriber(participant, config);
  const std::string params_text =
      "dds:\n  domain_id: " + std::to_string(config.domain_id) +
      "\n  cyclone_uri: " + config.cyclone_uri + "\n  depth_topic: " + config.depth_topic +
      "\n  camera_info_topic: " + config.camera_info_topic + "\n  image_history_depth: 32\n";
  const std::string params = std::filesystem::temp_directory_path() /
                             ("jpcr_dds_play_" + std::to_string(getpid()) + ".yaml");
  { std::ofstream(params) << params_text; }
  Child child({play, "--dataset", kTumDir, "--config", kFr1, "--encoding", "32FC1", "--frames",
               "2:8", "--as-fast-as-possible", "--params", params, "--wait-subscribers", "10"});
  ASSERT_TRUE(child.started());
  const auto source = open_dataset(kTumDir, load_camera_yaml(kFr1));
  for (std::size_t i = 2; i < 8; ++i) {
    const std::optional<Frame> got = subscriber.wait_frame(milliseconds(10000));
    ASSERT_TRUE(got) << "frame " << i;
    const Frame want = source->load(i);
    EXPECT_NEAR(got->timestamp, want.timestamp, 1e-6);
    EXPECT_EQ(got->camera.fx, want.camera.fx);
    EXPECT_EQ(got->camera.distortion, want.camera.distortion);
    ASSERT_EQ(got->depth.size(), want.depth.size());
    for (std::size_t p = 0; p < want.depth.size(); ++p)
      ASSERT_EQ(got->depth[p], want.depth[p]) << "frame " << i << " pixel " << p;
  }
  EXPECT_EQ(child.wait(), 0);
  EXPECT_EQ(subscriber.samples_rejected(), 0u);
  std::filesystem::remove(params);
}

TEST(DdsProcesses, CurvatureMapRoundTripsThroughAnotherProcess) {
  const DdsConfig config = test::loopback_dds_config("relay");
  const std::string there = config.topic_prefix + "there", back = config.topic_prefix + "back";
  const DdsParticipant participant(config);
  const DdsQos qos{true, false, 4};
  const DdsWriter<RosImage> writer(participant, there, qos);
  const DdsReader<RosImage> reader(participant, back, qos);
  Child relay({"/proc/self/exe", "--relay", std::to_string(config.domain_id), config.cyclone_uri,
               there, back});
  ASSERT_TRUE(relay.started());
  ASSERT_TRUE(writer.wait_matched(1, milliseconds(10000)));
  ASSERT_TRUE(reader.wait_matched(1, milliseconds(10000)));

  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uniform(-50.0f, 50.0f);
  Image<Eigen::Vector2f> k(640, 480, Eigen::Vector2f::Zero());
  for (std::size_t i = 0; i < k.size(); ++i)
    k[i] =
        i % 5 == 0 ? Eigen::Vector2f::Constant(NAN) : Eigen::Vector2f(uniform(rng), uniform(rng));
  const RosImageBuffer bytes = encode_curvature_image(k);
  const std::string frame = "camera";
  writer.write(image_message(bytes, 42.5, frame));
  std::optional<Image<Eigen::Vector2f>> got;
  ASSERT_TRUE(test::eventually(
      [&] {
        reader.wait(milliseconds(50));
        reader.take([&](const RosImage& m) { got = decode_curvature_image(image_view_of(m), {}); });
        return got.has_value();
      },
      milliseconds(10000)));
  EXPECT_EQ(std::memcmp(got->data(), k.data(), k.size() * sizeof(Eigen::Vector2f)), 0);
  EXPECT_EQ(relay.wait(), 0);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// jpcr_dds_echo in another process: joins after the path was published and still gets it
// (transient local), then prints the odometry published once it is matched.
TEST(DdsProcesses, EchoReceivesTheLastPathAsLateJoinerAndOdometry) {
  const std::string echo = std::string(JPCR_BINARY_DIR) + "/tools/jpcr_dds_echo";
  if (!std::filesystem::exists(echo)) GTEST_SKIP() << echo << " not built";
  const DdsConfig config = test::loopback_dds_config("echo");
  const DdsParticipant participant(config);
  DdsResultPublisher publisher(participant, config);
  Trajectory path;
  for (int i = 0; i < 4; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0.5 * i, -1.0, 2.0);
    path.push_back(StampedPose{100.0 + i, T});
  }
  publisher.publish_path(path);
  const std::string out_path = std::filesystem::temp_directory_path() /
                               ("jpcr_dds_echo_" + std::to_string(getpid()) + ".txt");
  const std::string domain = std::to_string(config.domain_id);
  Child path_echo({echo, result_topic_name(config, ResultTopic::kPath), "--domain", domain,
                   "--cyclone-uri", config.cyclone_uri, "--count", "1", "--timeout", "10"},
                  out_path);
  ASSERT_TRUE(path_echo.started());
  EXPECT_EQ(path_echo.wait(), 0);
  EXPECT_EQ(read_text(out_path),
            "path stamp=103.000000000 frame=map poses=4 last position=[1.5000 -1.0000 2.0000] "
            "orientation=[0.0000 0.0000 0.0000 1.0000]\n");

  Child odom_echo({echo, result_topic_name(config, ResultTopic::kOdometry), "--domain", domain,
                   "--cyclone-uri", config.cyclone_uri, "--count", "1", "--timeout", "10"},
                  out_path);
  ASSERT_TRUE(odom_echo.started());
  ASSERT_TRUE(test::eventually([&] { return publisher.matched(ResultTopic::kOdometry) == 1; },
                               milliseconds(10000)));
  publisher.publish_odometry(path.back(), Matrix6d::Identity() * 0.25);
  EXPECT_EQ(odom_echo.wait(), 0);
  EXPECT_EQ(read_text(out_path),
            "odom stamp=103.000000000 frame=map child=camera_depth_optical_frame "
            "position=[1.5000 -1.0000 2.0000] orientation=[0.0000 0.0000 0.0000 1.0000] "
            "cov_diag=[0.25 0.25 0.25 0.25 0.25 0.25]\n");
  std::filesystem::remove(out_path);
}

// The relay: forwards one image from topic FROM to topic TO, then exits 0 (1 after 20 s).
int relay(int domain, const std::string& uri, const std::string& from, const std::string& to) {
  const DdsParticipant participant(domain, uri);
  const DdsQos qos{true, false, 4};
  const DdsReader<RosImage> reader(participant, from, qos);
  const DdsWriter<RosImage> writer(participant, to, qos);
  bool done = false;
  const bool ok = test::eventually(
      [&] {
        reader.wait(milliseconds(50));
        reader.take([&](const RosImage& m) {
          writer.write(m);
          done = true;
        });
        return done;
      },
      milliseconds(20000));
  return ok && writer.wait_for_acks(milliseconds(5000)) ? 0 : 1;
}

}  // namespace
}  // namespace jpcr

int main(int argc, char** argv) {
  if (argc == 6 && std::strcmp(argv[1], "--relay") == 0) {
    return jpcr::relay(std::atoi(argv[2]), argv[3], argv[4], argv[5]);
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
