// jpcr_dds_echo: subscribes to one DDS topic of a ROS 2 type and prints one summary line per
// sample (stamp, frame, pose or image layout, whether an image decodes and why not).
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <string>
#include <type_traits>

#include <dds/dds.h>

#include "cli/arguments.hpp"
#include "cli/dds_options.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/io/dds/dds_config.hpp"
#include "jpcr/io/dds/ros_messages.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr_dds_echo/message_summary.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

const std::vector<std::string> kTypes = {"odom",        "pose",     "path",        "image",
                                         "camera_info", "keyframe", "curvature_sd"};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The type a topic name suggests: .../odom, .../keyframe_pose, .../path, .../camera_info,
// .../keyframe, .../curvature_sd (an image of sd values); anything else is an image.
std::string type_of_topic(const std::string& topic) {
  if (ends_with(topic, "curvature_sd")) return "curvature_sd";
  if (ends_with(topic, "odom")) return "odom";
  if (ends_with(topic, "pose")) return "pose";
  if (ends_with(topic, "path")) return "path";
  if (ends_with(topic, "camera_info")) return "camera_info";
  if (ends_with(topic, "keyframe")) return "keyframe";
  return "image";
}

struct EchoOptions {
  std::string topic;
  DdsQos qos;
  int count = 0;              // 0: until timeout or signal
  double timeout = 0.0;       // s, 0: none
  bool tum = false;           // paths: also every pose as TUM lines at full precision
  bool curvature_sd = false;  // images: summarised as curvature sd maps
};

// What a publisher offers that this reader cannot match, in the terms of the options above.
std::string incompatible_policy(uint32_t id) {
  if (id == DDS_RELIABILITY_QOS_POLICY_ID)
    return "reliability: a best-effort publisher needs --best-effort";
  if (id == DDS_DURABILITY_QOS_POLICY_ID)
    return "durability: a volatile publisher keeps nothing for --transient-local";
  return "QoS policy " + std::to_string(id);
}

template <typename Msg>
int echo(const DdsParticipant& participant, const EchoOptions& o) {
  const DdsReader<Msg> reader(participant, o.topic, o.qos);
  const Clock::time_point start = Clock::now();
  constexpr std::chrono::milliseconds kSlice{100};  // signal polling interval while waiting
  int received = 0;
  // std::cout fails once its reader is gone (| head: SIGPIPE is ignored, cli::run_program).
  while (!cli::stop_requested() && std::cout && (o.count == 0 || received < o.count)) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (o.timeout > 0.0 && elapsed >= o.timeout) break;
    reader.wait(kSlice);
    reader.take([&](const Msg& m) {
      if (o.count != 0 && received >= o.count) return;
      ++received;
      if constexpr (std::is_same_v<Msg, RosImage>)
        std::cout << (o.curvature_sd ? summarize_curvature_sd(m) : summarize(m)) << std::endl;
      else
        std::cout << summarize(m) << std::endl;
      if constexpr (std::is_same_v<Msg, RosPath>) {
        if (o.tum) {
          try {  // another publisher's path may hold a pose that is none: said, not fatal
            std::cout << format_trajectory(trajectory_of(m)) << std::flush;
          } catch (const InputError& e) {
            std::cerr << "jpcr_dds_echo: path sample " << received << ": " << e.what()
                      << "; its poses are not printed\n";
          }
        }
      }
    });
  }
  if (!std::cout) {
    if (errno == EPIPE) return 0;  // the reader of the output has what it wanted
    std::cerr << "jpcr_dds_echo: error: cannot write the output: " << std::strerror(errno) << '\n';
    return 1;
  }
  // A publisher this reader cannot match sends nothing, silently: say so (the node does too).
  dds_requested_incompatible_qos_status_t qos{};
  if (dds_get_requested_incompatible_qos_status(reader.handle(), &qos) == DDS_RETCODE_OK &&
      qos.total_count > 0) {
    std::cerr << "jpcr_dds_echo: " << qos.total_count << " publisher(s) on " << o.topic
              << " offer a QoS this reader cannot match ("
              << incompatible_policy(qos.last_policy_id) << "); their samples do not arrive\n";
  }
  if (o.count > 0 && received < o.count && !cli::stop_requested()) {
    std::cerr << "jpcr_dds_echo: received " << received << " of " << o.count << " samples on "
              << o.topic << " within " << o.timeout << " s\n";
    return 1;
  }
  return 0;
}

int run(int argc, char** argv) {
  cli::Arguments args("jpcr_dds_echo",
                      "Subscribes to a DDS topic carrying a ROS 2 message and prints one summary\n"
                      "line per sample. The Cyclone configuration comes from dds.cyclone_uri or\n"
                      "$CYCLONEDDS_URI.");
  args.positional("TOPIC", "DDS topic name, e.g. rt/jpcr/odom or rt/camera/depth/image_raw")
      .option("type",
              "odom | pose | path | image | camera_info | keyframe | curvature_sd (default: from "
              "the topic name; image otherwise)")
      .option("count", "exit after N samples (0: run until --timeout or Ctrl-C)", "0")
      .option("timeout",
              "seconds to listen, up to 86400 (0: no limit); fewer than --count samples is an "
              "error",
              "0")
      .flag("tum", "with a path: also print its poses as TUM lines (full precision)")
      .flag("best-effort", "subscribe best effort (matches sensor-data publishers too)")
      .flag("transient-local",
            "subscribe transient local: also get the samples the publisher kept before this\n"
            "reader matched (jpcr's results: the last history_depth, or image_history_depth\n"
            "images); matches transient-local publishers only");
  cli::add_dds_options(args);
  args.epilog(
      "Samples are read reliable, keeping dds.history_depth of them, unless --best-effort.\n"
      "Path is always read transient-local (the paths the node keeps arrive on joining: the\n"
      "last one, or with pipeline.keep_history: false up to history_depth of them); the other\n"
      "types volatile unless --transient-local. Every jpcr result topic is transient local, so\n"
      "--transient-local on one loses no sample to discovery, even one written before this\n"
      "reader was matched.\n\nexample:\n"
      "  jpcr_dds_echo rt/jpcr/odom --count 5 --timeout 10");
  return cli::run_program("jpcr_dds_echo", [&] {
    if (!args.parse(argc, argv)) return 0;
    EchoOptions o;
    o.topic = args.get("TOPIC");
    try {  // Cyclone says only "Bad Parameter"; a ROS name would match no DDS topic
      check_topic_name("TOPIC", o.topic);
    } catch (const InputError& e) {
      throw cli::UsageError(e.what());
    }
    const std::string type = args.has("type") ? args.get("type") : type_of_topic(o.topic);
    if (std::find(kTypes.begin(), kTypes.end(), type) == kTypes.end()) {
      throw cli::UsageError(
          "--type must be odom, pose, path, image, camera_info, keyframe or curvature_sd, got '" +
          type + "'");
    }
    o.count = args.get_int("count");
    if (o.count < 0) throw cli::UsageError("--count must be >= 0");
    o.timeout = args.get_double("timeout");
    o.tum = args.get_flag("tum");
    o.curvature_sd = type == "curvature_sd";
    // A finite bound: "inf" or 1e999 would be a listener that never stops, as 0 says on purpose.
    if (!(o.timeout >= 0.0 && o.timeout <= 86400.0))
      throw cli::UsageError("--timeout must be 0..86400 s (0: no limit)");
    const DdsConfig dds = cli::dds_config_from(args);
    o.qos.depth = dds.history_depth;
    o.qos.reliable = !args.get_flag("best-effort");
    // Transient local for the last path on joining; history_depth deep for the incremental
    // paths of keep_history: false, each of which carries poses no other path does.
    o.qos.transient_local = type == "path" || args.get_flag("transient-local");
    const DdsParticipant participant(dds);
    cli::install_stop_signal_handler();
    if (type == "odom") return echo<RosOdometry>(participant, o);
    if (type == "pose") return echo<RosPoseStamped>(participant, o);
    if (type == "path") return echo<RosPath>(participant, o);
    if (type == "camera_info") return echo<RosCameraInfoMsg>(participant, o);
    if (type == "keyframe") return echo<RosKeyframe>(participant, o);
    return echo<RosImage>(participant, o);
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run(argc, argv);
}
