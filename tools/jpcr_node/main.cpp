// jpcr_node: the live system over DDS. Subscribes a ROS 2 depth camera (sensor_msgs/Image 16UC1
// or 32FC1 + sensor_msgs/CameraInfo, the dds: section's topics), runs every received frame
// through the KeyframePipeline and publishes odom, keyframe_pose, curvature, curvature_color and
// path (cli/pipeline_publisher.hpp). Stops cleanly on SIGINT/SIGTERM, after --max-frames frames,
// or when no frame arrived for --idle-timeout seconds after the first: finishes the pipeline,
// publishes the final path, waits for the readers' acknowledgements and exits 0.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>

#include "cli/arguments.hpp"
#include "cli/dds_options.hpp"
#include "cli/pipeline_options.hpp"
#include "cli/pipeline_publisher.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/io/dds/dds_depth_subscriber.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

int node_main(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_node",
      "Runs jpcr live over DDS: every depth frame received on the dds: section's depth_topic\n"
      "(with its camera_info) goes through the keyframe pipeline (--method pipeline: ICP-ftf\n"
      "front end, J-ftf per keyframe pair, J-full per window; or one of the paper's methods).\n"
      "Publishes under dds.topic_prefix (default rt/jpcr/): odom per frame (the frame's\n"
      "refined-so-far pose with the front end's ICP covariance, zero for the first frame),\n"
      "keyframe_pose + curvature (32FC2) + curvature_color (rgb8) when a keyframe's map is\n"
      "final, and path (all refined poses, transient local) after every keyframe and at the\n"
      "end. Malformed input samples are dropped with one log line each.\n"
      "Stops on SIGINT/SIGTERM, --max-frames or --idle-timeout: finishes the pipeline,\n"
      "publishes the final path, flushes and exits 0.");
  args.option("method",
              "pipeline | icp-ftf | j-ftf | j-full | q-full | icp-bundle (default: params)")
      .option("window", "keyframes per J-full / Q-full window, 2-16 (default: params)")
      .option("max-frames", "stop after N processed frames (0: no limit)", "0")
      .option("idle-timeout",
              "stop when no frame arrived for S seconds after the first one (0: never)", "0")
      .option("flush-timeout", "seconds to wait for the readers' acknowledgements at exit", "5");
  cli::add_dds_options(args);
  args.epilog(
      "example:\n  export CYCLONEDDS_URI=file://$PWD/configs/cyclonedds_loopback.xml\n"
      "  jpcr_node --method j-ftf --idle-timeout 5 &\n"
      "  jpcr_dds_play --dataset seq --encoding 32FC1\n"
      "  jpcr_dds_echo rt/jpcr/path --timeout 2");
  return cli::run_program("jpcr_node", [&] {
    if (!args.parse(argc, argv)) return 0;
    Params params;
    PipelineParams pipeline = cli::pipeline_params_from(args, &params);
    const int max_frames = args.get_int("max-frames");
    if (max_frames < 0) throw cli::UsageError("--max-frames must be >= 0");
    const double idle_timeout = args.get_double("idle-timeout");
    if (!(idle_timeout >= 0.0)) throw cli::UsageError("--idle-timeout must be >= 0");
    const double flush_timeout = args.get_double("flush-timeout");
    if (!(flush_timeout >= 0.0)) throw cli::UsageError("--flush-timeout must be >= 0");
    pipeline.validate();
    const DdsConfig dds = cli::dds_config_from(args);

    const DdsParticipant participant(dds);
    DdsDepthSubscriber subscriber(participant, dds);
    cli::PipelinePublisher publisher(participant, dds);
    std::optional<KeyframePipeline> runner;
    runner.emplace(pipeline, [&](int keyframe, const Frame&, const QuadricMap& quadrics) {
      publisher.keyframe_final(*runner, keyframe, quadrics);
    });
    cli::install_stop_signal_handler();
    std::cerr << "jpcr_node: method " << to_string(pipeline.method) << ", window "
              << pipeline.window << ", listening on " << dds.depth_topic << " (domain "
              << dds.domain_id << "), publishing " << dds.topic_prefix << "*\n";

    const Clock::time_point start = Clock::now();
    const bool terminal = isatty(2) != 0;
    std::optional<Clock::time_point> last_frame;
    std::size_t processed = 0, skipped = 0;
    std::string reason = "signal";
    constexpr std::chrono::milliseconds kSlice{100};  // signal and idle polling interval
    while (!cli::stop_requested()) {
      if (max_frames > 0 && processed >= static_cast<std::size_t>(max_frames)) {
        reason = "--max-frames";
        break;
      }
      std::optional<Frame> frame = subscriber.wait_frame(kSlice);
      if (!frame) {
        if (last_frame && idle_timeout > 0.0 && seconds_since(*last_frame) >= idle_timeout) {
          reason = "--idle-timeout";
          break;
        }
        continue;
      }
      last_frame = Clock::now();
      const PipelineFrame* f = nullptr;
      try {
        f = &runner->add(*frame);
      } catch (const InputError& e) {  // e.g. a frame of another size than the first
        ++skipped;
        std::cerr << "jpcr_node: skipped the frame at stamp " << frame->timestamp << ": "
                  << e.what() << '\n';
        continue;
      }
      publisher.frame_added(*runner, *f);
      ++processed;
      // On a terminal the line is rewritten in place; in a log: frames 1-10, then every 10th.
      if (!terminal && processed > 10 && processed % 10 != 0) continue;
      std::fprintf(stderr,
                   "%sjpcr_node: frame %zu  keyframes %zu  icp %s%s  rejected %zu  %.1f s%s",
                   terminal ? "\r" : "", processed, runner->keyframes().size(),
                   to_string(f->icp_verdict), f->kept_last_motion ? " (kept last motion)" : "",
                   subscriber.samples_rejected(), seconds_since(start), terminal ? "" : "\n");
    }
    if (terminal && processed > 0) std::fputc('\n', stderr);
    if (processed > 0) {
      runner->finish();
      publisher.finished(*runner);
    }
    const bool flushed =
        publisher.flush(std::chrono::milliseconds(static_cast<long long>(flush_timeout * 1000.0)));
    if (!flushed) std::cerr << "jpcr_node: not every reader acknowledged the last samples\n";
    std::cout << "processed " << processed << " frames, " << runner->keyframes().size()
              << " keyframes, " << publisher.keyframes_published() << " curvature maps; rejected "
              << subscriber.samples_rejected() << " samples, skipped " << skipped
              << " frames; stopped by " << reason << '\n';
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::node_main(argc, argv);
}
