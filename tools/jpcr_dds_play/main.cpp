// jpcr_dds_play: publishes a dataset (TUM directory, synthetic sequence, MRPT rawlog) the way a
// ROS 2 depth camera does: sensor_msgs/CameraInfo + sensor_msgs/Image (16UC1 mm or 32FC1 m) on
// the dds: section's depth_topic and camera_info_topic, at the recorded rate or faster.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <thread>

#include "cli/arguments.hpp"
#include "cli/dds_options.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/dds/dds_depth_publisher.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

int run(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_dds_play",
      "Publishes a depth dataset over DDS as a ROS 2 depth camera would: a\n"
      "sensor_msgs/CameraInfo and a sensor_msgs/Image (16UC1 in mm or 32FC1 in m) per\n"
      "frame, stamped with the frame's timestamp, on the topics of the dds: section\n"
      "(default rt/camera/depth/image_raw and rt/camera/depth/camera_info).\n"
      "The Cyclone configuration comes from dds.cyclone_uri or $CYCLONEDDS_URI.\n"
      "With dds: {input_history: keep_all} in --params (and in jpcr_node's), the image\n"
      "writer is reliable KEEP_ALL and waits while the node's queue is full: every frame\n"
      "is processed, at the node's pace. Otherwise frames a slow node cannot take are\n"
      "dropped (counted by the node).");
  args.required("dataset", "TUM RGB-D directory, jpcr_synth output or MRPT .rawlog")
      .option("config", "camera YAML (default: the dataset's own camera)")
      .option("encoding", "depth encoding: 16UC1 (mm) | 32FC1 (m)", "16UC1")
      .option("rate", "playback speed relative to the recorded timestamps (default: 1)")
      .flag("as-fast-as-possible", "publish without waiting between frames")
      .option("frames",
              "FIRST:LAST, 0-based, LAST excluded (either may be empty), or N for frame N "
              "alone (default: all)")
      .option("wait-subscribers",
              "seconds to wait before the first frame for a subscriber of both the image and "
              "the camera_info topic (as a ROS 2 depth consumer subscribes)",
              "2");
  cli::add_dds_options(args);
  args.epilog(
      "example (the image topic keeps no history: start the subscriber first):\n"
      "  export CYCLONEDDS_URI=file://$PWD/configs/cyclonedds_loopback.xml\n"
      "  jpcr_dds_echo rt/camera/depth/image_raw --count 10 &\n"
      "  jpcr_dds_play --dataset tests/data/tum_fr1_xyz_20 --config configs/tum_fr1.yaml");
  return cli::run_program("jpcr_dds_play", [&] {
    if (!args.parse(argc, argv)) return 0;
    DepthEncoding encoding;
    try {
      encoding = parse_depth_encoding(args.get("encoding"));
    } catch (const InputError& e) {
      throw cli::UsageError(std::string("--encoding: ") + e.what());
    }
    const double rate = args.has("rate") ? args.get_double("rate") : 1.0;
    // Bounded so that the waits they imply fit the clock's duration type (1e10 s overflowed
    // into no wait at all).
    if (!(rate >= 1e-3 && rate <= 1e6)) throw cli::UsageError("--rate must be in 0.001..1e6");
    const double wait_seconds = args.get_double("wait-subscribers");
    if (!(wait_seconds >= 0.0 && wait_seconds <= 86400.0))
      throw cli::UsageError("--wait-subscribers must be 0..86400 s");
    const bool fast = args.get_flag("as-fast-as-possible");
    if (fast && args.has("rate"))
      std::cerr << "jpcr_dds_play: warning: --rate has no effect with --as-fast-as-possible\n";
    const DdsConfig dds = cli::dds_config_from(args);
    std::optional<CameraIntrinsics> camera;
    if (args.has("config")) camera = load_camera_yaml(args.get("config"));
    const std::unique_ptr<FrameSource> source = open_dataset(args.get("dataset"), camera);
    std::size_t first = 0, last = source->size();
    if (source->size() == 0) throw InputError(source->description() + " has no frames");
    if (args.has("frames")) {
      const cli::FrameRange range = cli::parse_frame_range(args.get("frames"), source->size());
      first = range.first;
      last = range.last;
    }

    const DdsParticipant participant(dds);
    DdsDepthPublisher publisher(participant, dds, encoding);
    cli::install_stop_signal_handler();
    std::cerr << "jpcr_dds_play: " << source->description() << ", frames " << first << ".."
              << last - 1 << " as " << to_string(encoding) << " on " << dds.depth_topic
              << " (domain " << dds.domain_id << ")\n";
    const auto wait = std::chrono::milliseconds(static_cast<long long>(wait_seconds * 1000.0));
    if (!publisher.wait_for_subscribers(1, wait, [] { return !cli::stop_requested(); }) &&
        wait_seconds > 0.0 && !cli::stop_requested()) {
      std::cerr << "jpcr_dds_play: no subscriber of both " << dds.depth_topic << " and "
                << dds.camera_info_topic << " after " << wait_seconds << " s; publishing anyway\n";
    }

    constexpr double kMaxWait = 86400.0;  // s from the first frame, at --rate
    const Clock::time_point start = Clock::now();
    cli::Progress progress("jpcr_dds_play", start);
    const double t0 = source->timestamp(first);
    std::size_t published = 0;
    for (std::size_t i = first; i < last && !cli::stop_requested(); ++i) {
      const Frame frame = source->load(i);
      if (!fast) {
        // Past about 292 years the clock's nanoseconds overflow (a gap of 1e300 s was no wait at
        // all); far before that, a wait of days means timestamps that are no recording's.
        const double offset = (frame.timestamp - t0) / rate;
        if (!(offset <= kMaxWait))
          throw InputError(args.get("dataset") + ": frame " + std::to_string(i) + " is stamped " +
                           format_double(frame.timestamp - t0) + " s after frame " +
                           std::to_string(first) + ": playing it at a rate of " +
                           format_double(rate) + " would wait more than " +
                           std::to_string(static_cast<long>(kMaxWait)) +
                           " s (--as-fast-as-possible publishes without waiting)");
        const auto due = start + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(offset));
        while (Clock::now() < due && !cli::stop_requested())
          std::this_thread::sleep_for(
              std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(50)));
        if (cli::stop_requested()) break;
      }
      // dds.input_history: keep_all: waits while the subscriber's queue is full.
      if (!publisher.publish(frame, [] { return !cli::stop_requested(); })) break;
      ++published;
      progress(published, last - first);
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    constexpr std::chrono::milliseconds kFlushTimeout{2000};  // for the last frames to be acked
    if (!publisher.flush(kFlushTimeout))
      std::cerr << "jpcr_dds_play: warning: a subscriber had not acknowledged the last frames "
                   "after "
                << kFlushTimeout.count() / 1000.0
                << " s (a slow or stalled reader); they may not have arrived\n";
    std::cout << "published " << published << " frames in " << seconds << " s ("
              << published / std::max(seconds, 1e-9) << " frames/s) on " << dds.depth_topic
              << (cli::stop_requested() ? ", stopped by signal" : "") << '\n';
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run(argc, argv);
}
