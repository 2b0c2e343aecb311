// bench_dds_latency: publish-to-receive latency over Cyclone DDS on loopback, for a pose
// (geometry_msgs/PoseStamped) and a 640x480 32FC2 curvature map (sensor_msgs/Image, 2.4 MB).
// The subscriber is a second process (this program re-executed with --subscribe), so samples
// cross the loopback interface as they would between jpcr_node and a ROS 2 node. Each sample
// carries its CLOCK_MONOTONIC send time in header.stamp; the subscriber subtracts it from its
// receive time (same clock, same machine) and reports the latencies back through a pipe.
//
//   bench_dds_latency [--samples N] [--domain D] [--cyclone-uri URI]
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "jpcr/io/dds/ros_messages.hpp"

namespace jpcr {

namespace {

constexpr int kWarmup = 20;                             // samples not timed
constexpr std::chrono::milliseconds kPoseInterval{2};   // between pose samples
constexpr std::chrono::milliseconds kMapInterval{15};   // between map samples (2.4 MB each)
constexpr std::chrono::seconds kSubscriberTimeout{60};  // the subscriber gives up after this
const char* const kWarmupFrame = "warmup";

struct Options {
  int samples = 300;
  int domain = 0;
  std::string uri = "file://" JPCR_SOURCE_DIR "/configs/cyclonedds_loopback.xml";
};

std::int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1000000000 + ts.tv_nsec;
}

std::string topic_of(const std::string& kind, int domain) {
  return "rt/jpcr_bench_" + std::to_string(domain) + "/" + kind;
}

// Subscriber process: receives `samples` timed samples, writes their latencies (ns, int64) to
// stdout in binary, exits.
template <typename Msg>
int subscribe(const Options& o, const std::string& kind) {
  const DdsParticipant participant(o.domain, o.uri);
  const DdsReader<Msg> reader(participant, topic_of(kind, o.domain), DdsQos{true, false, 16});
  std::vector<std::int64_t> latencies;
  const auto deadline = std::chrono::steady_clock::now() + kSubscriberTimeout;
  while (static_cast<int>(latencies.size()) < o.samples &&
         std::chrono::steady_clock::now() < deadline) {
    reader.wait(std::chrono::milliseconds(100));
    reader.take([&](const Msg& m) {
      const std::int64_t now = monotonic_ns();
      if (std::strcmp(m.header.frame_id, kWarmupFrame) == 0) return;
      const std::int64_t sent =
          std::int64_t{m.header.stamp.sec} * 1000000000 + m.header.stamp.nanosec;
      latencies.push_back(now - sent);
    });
  }
  std::fwrite(latencies.data(), sizeof(std::int64_t), latencies.size(), stdout);
  std::fflush(stdout);
  return 0;
}

std_msgs_msg_dds__Header_ stamped_now(const std::string& frame_id) {
  std_msgs_msg_dds__Header_ h{};
  const std::int64_t now = monotonic_ns();
  h.stamp.sec = static_cast<std::int32_t>(now / 1000000000);
  h.stamp.nanosec = static_cast<std::uint32_t>(now % 1000000000);
  h.frame_id = const_cast<char*>(frame_id.c_str());
  return h;
}

struct Result {
  std::string name;
  std::size_t bytes = 0;
  int sent = 0;
  std::vector<std::int64_t> latencies;
};

// Starts the subscriber process for `kind`, publishes warm-up and timed samples, and collects the
// latencies it measured.
template <typename Msg, typename Make>
Result run_case(const Options& o, const std::string& kind, const std::string& name,
                std::chrono::milliseconds interval, Make make) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t child = fork();
  if (child == 0) {
    dup2(fds[1], 1);
    close(fds[0]);
    close(fds[1]);
    const std::string samples = std::to_string(o.samples), domain = std::to_string(o.domain);
    execl("/proc/self/exe", "bench_dds_latency", "--subscribe", kind.c_str(), "--samples",
          samples.c_str(), "--domain", domain.c_str(), "--cyclone-uri", o.uri.c_str(), nullptr);
    _exit(127);
  }
  close(fds[1]);
  Result r;
  r.name = name;
  {
    const DdsParticipant participant(o.domain, o.uri);
    const DdsWriter<Msg> writer(participant, topic_of(kind, o.domain), DdsQos{true, false, 16});
    if (!writer.wait_matched(1, std::chrono::seconds(10))) {
      throw std::runtime_error("the subscriber process did not match within 10 s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // both sides matched
    const std::string warmup = kWarmupFrame, timed = "bench";
    for (int i = 0; i < kWarmup + o.samples; ++i) {
      const std::string& frame = i < kWarmup ? warmup : timed;
      r.bytes = make([&](Msg& m) {
        m.header = stamped_now(frame);
        writer.write(m);
      });
      std::this_thread::sleep_for(interval);
    }
    r.sent = o.samples;
    writer.wait_for_acks(std::chrono::seconds(5));
    std::int64_t v;
    while (read(fds[0], &v, sizeof v) == static_cast<ssize_t>(sizeof v))
      r.latencies.push_back(v);
  }
  close(fds[0]);
  int status = 0;
  waitpid(child, &status, 0);
  return r;
}

double percentile_ms(std::vector<std::int64_t> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5));
  return v[i] * 1e-6;
}

int run(int argc, char** argv) {
  Options o;
  o.domain = 100 + static_cast<int>(getpid() % 100);
  std::string subscribe_kind;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--samples")
      o.samples = std::stoi(value);
    else if (flag == "--domain")
      o.domain = std::stoi(value);
    else if (flag == "--cyclone-uri")
      o.uri = value;
    else if (flag == "--subscribe")
      subscribe_kind = value;
    else {
      std::cerr << "usage: bench_dds_latency [--samples N] [--domain D] [--cyclone-uri URI]\n";
      return 2;
    }
  }
  if (argc % 2 == 0 || o.samples < 1) {
    std::cerr << "usage: bench_dds_latency [--samples N] [--domain D] [--cyclone-uri URI]\n";
    return 2;
  }
  if (subscribe_kind == "pose") return subscribe<RosPoseStamped>(o, subscribe_kind);
  if (subscribe_kind == "map") return subscribe<RosImage>(o, subscribe_kind);

  const StampedPose pose{0.0, Eigen::Isometry3d::Identity()};
  Image<Eigen::Vector2f> map(640, 480, Eigen::Vector2f(0.5f, -0.25f));
  const RosImageBuffer map_bytes = encode_curvature_image(map);
  const std::string frame = "camera";
  std::vector<Result> results;
  results.push_back(
      run_case<RosPoseStamped>(o, "pose", "PoseStamped", kPoseInterval, [&](auto send) {
        RosPoseStamped m = pose_stamped_message(pose, frame);
        send(m);
        return std::size_t{7 * sizeof(double)};  // position and orientation
      }));
  results.push_back(
      run_case<RosImage>(o, "map", "Image 640x480 32FC2", kMapInterval, [&](auto send) {
        RosImage m = image_message(map_bytes, 0.0, frame);
        send(m);
        return map_bytes.data.size();
      }));

  std::printf("Cyclone DDS loopback latency, publish -> receive in another process (%s)\n",
              o.uri.c_str());
  std::printf("%-22s %10s %8s %8s %10s %10s %10s\n", "message", "payload B", "sent", "received",
              "median ms", "p99 ms", "max ms");
  bool ok = true;
  for (const Result& r : results) {
    std::printf("%-22s %10zu %8d %8zu %10.3f %10.3f %10.3f\n", r.name.c_str(), r.bytes, r.sent,
                r.latencies.size(), percentile_ms(r.latencies, 0.5),
                percentile_ms(r.latencies, 0.99), percentile_ms(r.latencies, 1.0));
    ok = ok && static_cast<int>(r.latencies.size()) == r.sent;
  }
  return ok ? 0 : 1;
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  try {
    return jpcr::run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "bench_dds_latency: " << e.what() << '\n';
    return 1;
  }
}
