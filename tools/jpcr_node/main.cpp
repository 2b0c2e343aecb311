// jpcr_node: the live system over DDS. Subscribes a ROS 2 depth camera (sensor_msgs/Image 16UC1
// or 32FC1 + sensor_msgs/CameraInfo, the dds: section's topics), runs every received frame
// through the keyframe pipeline and publishes odom, keyframe_pose, curvature, curvature_color,
// curvature_sd and path (cli/pipeline_publisher.hpp). --role splits the pipeline over two
// processes joined by the keyframe topic (io/dds/dds_keyframe_link.hpp):
//   all       (default) front end and back end in this process (KeyframePipeline)
//   frontend  PipelineFrontEnd: depth in, odom (front-end poses) and keyframes out
//   backend   PipelineBackEnd: keyframes in, keyframe_pose, curvature(_color, _sd), path out
// Stops cleanly on SIGINT/SIGTERM, after --max-frames frames, when no input arrived for
// --idle-timeout seconds after the first, or (back end) at the front end's end of stream:
// finishes, publishes what is left, waits for the readers' acknowledgements and exits 0.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>

#include "cli/arguments.hpp"
#include "cli/dds_options.hpp"
#include "cli/device_option.hpp"
#include "cli/pipeline_options.hpp"
#include "cli/pipeline_publisher.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/backend/keyframe_pipeline.hpp"
#include "jpcr/cuda/refiner_factory.hpp"
#include "jpcr/io/dds/dds_depth_subscriber.hpp"
#include "jpcr/io/dds/dds_keyframe_link.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr_node/node_loop.hpp"

namespace jpcr {

namespace {

struct NodeOptions {
  PipelineParams pipeline;
  ComputeDevice device = ComputeDevice::kAuto;  // where J-ftf runs
  DdsConfig dds;
  node::StopRules stop;
  std::chrono::milliseconds flush_timeout{5000};
  std::chrono::milliseconds backend_wait{10000};
};

std::chrono::milliseconds milliseconds_of(double seconds) {
  return std::chrono::milliseconds(static_cast<long long>(seconds * 1000.0));
}

// Front end and back end in one process.
int run_all(const NodeOptions& o, const DdsParticipant& participant) {
  DdsDepthSubscriber subscriber(participant, o.dds);
  cli::PipelinePublisher publisher(participant, o.dds, o.pipeline.keep_history,
                                   o.pipeline.joint.quadric);
  std::optional<KeyframePipeline> runner;
  runner.emplace(
      o.pipeline,
      [&](int keyframe, const Frame& frame, const QuadricMap& quadrics) {
        publisher.keyframe_final(*runner, keyframe, frame, quadrics);
      },
      device_refiner_factory(o.device, std::cerr));
  publisher.attach(*runner);
  node::StampOrder order;  // live frames in time order
  node::Progress progress;
  const node::Outcome outcome = node::receive(
      o.stop, [&](auto slice) { return subscriber.wait_frame(slice); },
      [&](const Frame& frame) {
        // A frame the pipeline refuses (another camera's) leaves the order as it was.
        const node::StampOrder before = order;
        order.take(frame.timestamp);
        publisher.set_camera_frame_id(subscriber.frame_id());
        const PipelineFrame* added = nullptr;
        try {
          added = &runner->add(frame);
        } catch (...) {
          order = before;
          throw;
        }
        const PipelineFrame& f = *added;
        publisher.frame_added(*runner, f);
        progress.frame(f, runner->keyframe_count(), subscriber);
        return node::Step::kProcessed;
      });
  progress.done();
  // The input's counts as the loop ended: frames that arrive during the flush below are not
  // dropped ones (the subscriber keeps taking them).
  const std::string inputs = node::input_summary(subscriber);
  std::cerr << "jpcr_node: " << node::rate_summary(outcome, "frames") << '\n';
  if (outcome.processed > 0) {
    runner->finish();
    publisher.finished(*runner);
  }
  if (!publisher.flush(o.flush_timeout))
    std::cerr << "jpcr_node: not every reader acknowledged the last samples\n";
  std::cout << "processed " << outcome.processed << " frames, " << runner->keyframe_count()
            << " keyframes, " << publisher.keyframes_published() << " curvature maps ("
            << publisher.writes_failed() << " samples not published); " << inputs << ", skipped "
            << outcome.skipped << " frames; stopped by " << outcome.reason << '\n';
  return 0;
}

// The front-end process: ICP-ftf per frame, odom, keyframes to the back end.
int run_frontend(const NodeOptions& o, const DdsParticipant& participant) {
  DdsDepthSubscriber subscriber(participant, o.dds);
  DdsResultPublisher results(participant, o.dds);
  DdsKeyframeWriter keyframes(participant, o.dds);
  PipelineFrontEnd front_end(o.pipeline);
  Trajectory tracked;  // the front end's poses of the frames since the last keyframe
  std::size_t sent = 0;
  // The back end holds dds.keyframe_queue keyframes unread: the front end then waits for it (said
  // the first time, summed at the end); a stop signal gives the keyframe up.
  bool waiting = false;
  std::size_t waits = 0;
  double waited_total = 0.0;
  // A back end that took keyframes and is no longer matched (it crashed or was killed; Cyclone
  // notices when its lease runs out) cannot chain later ones: they are not sent, the run ends
  // with exit 1, odom goes on until then.
  bool had_back_end = false, end_written = false;
  std::string back_end_gone;
  const auto back_end_went_away = [&] {
    if (!back_end_gone.empty()) return true;
    if (end_written) return false;  // from here a back end that goes has finished
    if (keyframes.matched() > 0) {
      had_back_end = true;
      return false;
    }
    if (!had_back_end) return false;
    back_end_gone = "the back end on " + keyframe_topic_name(o.dds) + " went away; of the " +
                    std::to_string(sent) + " keyframes sent, those after it stopped are lost";
    std::cerr << "jpcr_node: error: " << back_end_gone
              << "; later keyframes are not sent (restart both to refine again)\n";
    return true;
  };
  const auto wait_for_back_end = [&](double) {
    if (back_end_went_away()) return false;
    if (!waiting && waits++ == 0)
      std::cerr << "jpcr_node: the back end has " << o.dds.keyframe_queue
                << " keyframes unread (dds.keyframe_queue); waiting for it\n";
    waiting = true;
    return !cli::stop_requested();
  };
  node::StopRules stop = o.stop;
  stop.source_gone = [&] {  // said as soon as it is seen, also while no frame comes; odom goes on
    back_end_went_away();
    return std::string();
  };
  node::StampOrder order;  // live frames in time order
  node::Progress progress;
  const node::Outcome outcome = node::receive(
      stop, [&](auto slice) { return subscriber.wait_frame(slice); },
      [&](const Frame& frame) {
        const node::StampOrder before = order;  // as in run_all
        order.take(frame.timestamp);
        results.set_camera_frame_id(subscriber.frame_id());
        keyframes.set_camera_frame_id(subscriber.frame_id());
        bool keyframe = false;
        PipelineFrame f;
        try {
          f = front_end.track(frame, &keyframe);
        } catch (...) {
          order = before;
          throw;
        }
        results.publish_odometry(
            f.front_end,
            position_rotation_covariance(f.pose_covariance, f.front_end.pose.translation()));
        if (back_end_went_away()) {
          tracked.clear();
        } else if (!keyframe) {
          tracked.push_back(f.front_end);
        } else {
          if (sent == 0 &&
              !keyframes.wait_matched(o.backend_wait,
                                      [](double) { return !cli::stop_requested(); }) &&
              !cli::stop_requested())
            std::cerr << "jpcr_node: no back end on " << keyframe_topic_name(o.dds)
                      << "; sending the keyframes anyway\n";
          waiting = false;
          const auto start = node::Clock::now();
          const bool sent_now = keyframes.publish(frame, f.front_end, f.icp_covariance, f.index,
                                                  tracked, wait_for_back_end);
          if (waiting) waited_total += node::seconds_since(start);
          if (sent_now) {
            tracked.clear();
            ++sent;
          } else {  // stopped while waiting: the end of stream carries it as a tracked frame
            tracked.push_back(f.front_end);
          }
        }
        progress.frame(f, sent, subscriber);
        return node::Step::kProcessed;
      });
  progress.done();
  // The input's counts as the loop ended: frames that arrive during the flush below are not
  // dropped ones (the subscriber keeps taking them).
  const std::string inputs = node::input_summary(subscriber);
  std::cerr << "jpcr_node: " << node::rate_summary(outcome, "frames") << '\n';
  if (back_end_went_away()) {
    if (!results.flush(o.flush_timeout))
      std::cerr << "jpcr_node: not every reader acknowledged the last samples\n";
    std::cout << "processed " << outcome.processed << " frames, sent " << sent
              << " keyframes, not the end of stream (" << back_end_gone << "); " << inputs
              << ", skipped " << outcome.skipped << " frames; stopped by " << outcome.reason
              << '\n';
    return 1;
  }
  // The end of stream, and the back end's acknowledgement of every keyframe, wait as a keyframe
  // does; after a signal, --flush-timeout at most.
  const auto wait_to_end = [&](double waited) {
    return wait_for_back_end(waited) || waited < o.flush_timeout.count() / 1000.0;
  };
  waiting = false;
  const auto start = node::Clock::now();
  const bool ended =
      keyframes.publish_end(static_cast<int>(outcome.processed), tracked, wait_to_end);
  end_written = ended;
  if (!ended && !back_end_gone.empty())
    std::cerr << "jpcr_node: end of stream not sent\n";
  else if (!ended)
    std::cerr << "jpcr_node: the back end took no keyframe within --flush-timeout after the signal;"
                 " end of stream not sent\n";
  bool flushed = ended && keyframes.flush(wait_to_end) && results.flush(o.flush_timeout);
  if (waiting) waited_total += node::seconds_since(start);
  // Keyframes a back end acknowledged but still holds are lost if we exit now (see
  // dds_keyframe_link.hpp): wait for the back ends to finish and go.
  if (ended && keyframes.matched() > 0) {
    std::cerr << "jpcr_node: waiting for the back end to finish (SIGINT/SIGTERM: stop waiting)\n";
    flushed = keyframes.wait_until_unmatched([&](double waited) {
      return !cli::stop_requested() || waited < o.flush_timeout.count() / 1000.0;
    }) && flushed;
  }
  if (waits > 0)
    std::cerr << "jpcr_node: waited " << waited_total << " s in all for the back end (" << waits
              << " times)\n";
  if (!flushed) std::cerr << "jpcr_node: not every reader acknowledged the last samples\n";
  std::cout << "processed " << outcome.processed << " frames, sent " << sent
            << (ended ? " keyframes and the end of stream; "
                      : " keyframes, not the end of stream; ")
            << inputs << ", skipped " << outcome.skipped << " frames; stopped by " << outcome.reason
            << '\n';
  return back_end_gone.empty() ? 0 : 1;  // gone while it ended: said above
}

// The back-end process: keyframes in, J-ftf / J-full, re-anchoring, results out.
int run_backend(const NodeOptions& o, const DdsParticipant& participant) {
  DdsKeyframeReader reader(participant, o.dds);
  cli::PipelinePublisher publisher(participant, o.dds, o.pipeline.keep_history,
                                   o.pipeline.joint.quadric);
  std::optional<PipelineBackEnd> back_end;
  back_end.emplace(
      o.pipeline,
      [&](int keyframe, const Frame& frame, const QuadricMap& quadrics) {
        publisher.keyframe_final(*back_end, keyframe, frame, quadrics);
      },
      device_refiner_factory(o.device, std::cerr));
  publisher.attach(*back_end);
  node::StopRules stop = o.stop;
  stop.max_items = 0;  // --max-frames belongs to the front end; its end of stream stops us
  // A front end that sent keyframes and is no longer matched without its end of stream (it
  // crashed or was killed; Cyclone notices when its lease runs out) sends no more: the back end
  // finishes what it has, publishes it and exits 1.
  bool had_front_end = false;
  std::string front_end_gone;
  stop.source_gone = [&]() -> std::string {
    if (reader.matched() > 0) {
      had_front_end = true;
      return {};
    }
    if (!had_front_end) return {};
    front_end_gone = "the front end went away after " + std::to_string(back_end->frame_count()) +
                     " frames without its end of stream";
    return "the front end going away";
  };
  node::Progress progress;
  // Each keyframe message continues the chain of the ones before it. Once one is lost (never
  // received, or refused: another camera), no later one can be chained to what was refined, so
  // the back end stops there, publishes what it has and exits 1.
  std::string lost;
  node::Outcome outcome = node::receive(
      stop, [&](auto slice) { return reader.wait(slice); },
      [&](const DecodedKeyframe& k) {
        const std::size_t first = static_cast<std::size_t>(k.frame_index) - k.tracked.size();
        if (first != back_end->frame_count()) {
          lost = "keyframe message for frames " + std::to_string(first) + ".." +
                 std::to_string(k.frame_index) + " after frame " +
                 std::to_string(back_end->frame_count()) +
                 ": keyframes were lost (start the back end before the front end)";
          return node::Step::kEndOfStream;
        }
        for (std::size_t i = 0; i < k.tracked.size(); ++i) {
          PipelineFrame f;
          f.index = static_cast<int>(first + i);
          f.front_end = k.tracked[i];
          // Frames before the first keyframe had no points to be aligned against (the message
          // carries no verdicts; the others' alignments are taken as ok).
          if (back_end->keyframe_count() == 0) f.icp_verdict = IcpVerdict::too_few_points;
          back_end->add(f, nullptr);
        }
        if (k.end_of_stream) return node::Step::kEndOfStream;
        publisher.set_camera_frame_id(k.camera_frame_id);
        PipelineFrame f;
        f.index = k.frame_index;
        f.front_end = k.pose;
        f.icp_covariance = k.covariance;
        try {
          back_end->add(f, &k.frame);
        } catch (const InputError& e) {
          lost = "keyframe of frame " + std::to_string(k.frame_index) + " refused: " + e.what();
          return node::Step::kEndOfStream;
        }
        publisher.path_if_refined(*back_end);
        progress.keyframe(back_end->keyframe_count(), back_end->frame_count());
        return node::Step::kProcessed;
      });
  if (!lost.empty()) outcome.reason = "a lost keyframe";
  progress.done();
  if (back_end->frame_count() > 0) {
    back_end->finish();
    publisher.finished(*back_end);
  }
  if (!publisher.flush(o.flush_timeout))
    std::cerr << "jpcr_node: not every reader acknowledged the last samples\n";
  std::cout << "refined " << back_end->keyframe_count() << " keyframes of "
            << back_end->frame_count() << " frames, " << publisher.keyframes_published()
            << " curvature maps (" << publisher.writes_failed()
            << " samples not published); rejected " << reader.samples_rejected()
            << " samples, skipped " << outcome.skipped << " messages; stopped by " << outcome.reason
            << '\n';
  if (!front_end_gone.empty()) {
    std::cerr << "jpcr_node: error: " << front_end_gone << "; the back end stopped there\n";
    return 1;
  }
  if (lost.empty()) return 0;
  std::cerr << "jpcr_node: error: " << lost << "; the back end stopped there\n";
  return 1;
}

int node_main(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_node",
      "Runs jpcr live over DDS: every depth frame received on the dds: section's depth_topic\n"
      "(with its camera_info) goes through the keyframe pipeline (--method pipeline: ICP-ftf\n"
      "front end, J-ftf per keyframe pair, J-full per window; or one of the paper's methods).\n"
      "Publishes under dds.topic_prefix (default rt/jpcr/): odom per frame (the frame's\n"
      "refined-so-far pose with the front end's covariance of it, accumulated along its\n"
      "alignments in map axes, zero for the gauge, the first frame with points, and\n"
      "1 m / 1 rad per axis for any frame before it),\n"
      "keyframe_pose + curvature (32FC2) + curvature_color (rgb8) + curvature_sd (32FC1, the\n"
      "map's sd per pixel; not with dds.curvature_sd: false) when a keyframe's map is\n"
      "final, and path (the refined poses, transient local) after every keyframe and at the\n"
      "end. For unattended runs set pipeline.keep_history: false in --params: each frame is\n"
      "forgotten once its pose is final and published, so memory stays bounded, and each path\n"
      "holds the frames made final since the previous one, then those still held.\n"
      "Malformed input samples are dropped with one log line each; "
      "frames the node is too\n"
      "slow for (more than dds.image_history_depth waiting) are dropped, counted and logged,\n"
      "unless dds.input_history is keep_all: a reliable keep_all camera (jpcr_dds_play with\n"
      "the same --params) then waits for the node and every frame is processed (not with\n"
      "--role frontend; a keep_last camera still loses frames, uncounted).\n"
      "--role frontend / backend split the pipeline over two processes (two hosts) joined by\n"
      "PREFIX keyframe: the front end publishes odom (its own poses) and sends each keyframe\n"
      "(depth, camera, pose, the poses of the frames since the previous keyframe); the back\n"
      "end refines and publishes keyframe_pose, curvature, curvature_color, curvature_sd and\n"
      "path, the same trajectory as --role all. Start the back end first; give both the same\n"
      "--params, --method and --window. A back end dds.keyframe_queue keyframes behind makes\n"
      "the front end wait for it; at the end the front end waits for the back end to finish.\n"
      "Stops on SIGINT/SIGTERM, --max-frames, --idle-timeout or (back end) the front end's\n"
      "end of stream: finishes the pipeline, publishes the final path, flushes and exits 0.");
  args.option("role", "all | frontend | backend", "all")
      .option("method",
              "pipeline | icp-ftf | j-ftf | j-full | q-full | icp-bundle (default: params)")
      .option("window", "keyframes per J-full / Q-full / ICP-bundle window, 2-16 (default: params)")
      .option("max-frames", "stop after N processed frames (0: no limit; not the back end)", "0")
      .option("idle-timeout",
              "stop when no input was processed for S seconds (up to 86400) after the first one "
              "(skipped ones do not count; 0: never)",
              "0")
      .option("flush-timeout",
              "seconds to wait for the readers' acknowledgements at exit (after a signal, also for "
              "the back end)",
              "5")
      .option("backend-wait",
              "front end: seconds to wait for a back end before sending the first keyframe", "10");
  cli::add_device_option(args);
  cli::add_dds_options(args);
  args.epilog(
      "examples:\n  export CYCLONEDDS_URI=file://$PWD/configs/cyclonedds_loopback.xml\n"
      "  jpcr_node --method j-ftf --idle-timeout 5 &\n"
      "  jpcr_dds_play --dataset seq --encoding 32FC1\n"
      "  jpcr_dds_echo rt/jpcr/path --timeout 2\n"
      "split (the back end may run on another host of the same DDS domain):\n"
      "  jpcr_node --role backend &\n"
      "  jpcr_node --role frontend --idle-timeout 5 &\n"
      "  jpcr_dds_play --dataset seq --encoding 32FC1");
  return cli::run_program("jpcr_node", [&] {
    if (!args.parse(argc, argv)) return 0;
    const std::string role = args.get("role");
    if (role != "all" && role != "frontend" && role != "backend")
      throw cli::UsageError("--role must be all, frontend or backend, got '" + role + "'");
    NodeOptions o;
    Params params;
    o.pipeline = cli::pipeline_params_from(args, &params);
    o.device = cli::device_from(args, params);
    o.stop.max_items = args.get_int("max-frames");
    if (o.stop.max_items < 0) throw cli::UsageError("--max-frames must be >= 0");
    if (role == "backend" && o.stop.max_items > 0)
      throw cli::UsageError(
          "--max-frames is the front end's; the back end stops at its end of "
          "stream (give it to --role frontend)");
    o.stop.idle_timeout = args.get_double("idle-timeout");
    // A finite bound, as the other timeouts: "inf" would mean what 0 says on purpose.
    if (!(o.stop.idle_timeout >= 0.0 && o.stop.idle_timeout <= 86400.0))
      throw cli::UsageError("--idle-timeout must be 0..86400 s (0: never)");
    // Bounded so that they fit the clock's milliseconds (inf became a negative wait: none).
    const double flush_timeout = args.get_double("flush-timeout");
    if (!(flush_timeout >= 0.0 && flush_timeout <= 86400.0))
      throw cli::UsageError("--flush-timeout must be 0..86400 s");
    o.flush_timeout = milliseconds_of(flush_timeout);
    const double backend_wait = args.get_double("backend-wait");
    if (!(backend_wait >= 0.0 && backend_wait <= 86400.0))
      throw cli::UsageError("--backend-wait must be 0..86400 s");
    o.backend_wait = milliseconds_of(backend_wait);
    o.pipeline.validate();
    o.dds = cli::dds_config_from(args);
    // Cyclone holds a KEEP_ALL camera back by retrying the full reader on its receive thread, so
    // nothing else reaches the process meanwhile, the back end's acknowledgements included: the
    // front end, waiting for them to send a keyframe, never takes the next image (a deadlock,
    // review of 2026-12-06).
    if (role == "frontend" && o.dds.input_keep_all)
      throw InputError(
          "dds.input_history: keep_all cannot pace a split front end (its keyframe queue waits for "
          "acknowledgements that the held-back input blocks); use keep_last with a deep "
          "image_history_depth, or --role all");

    const DdsParticipant participant(o.dds);
    cli::install_stop_signal_handler();
    std::cerr << "jpcr_node: role " << role << ", method " << to_string(o.pipeline.method)
              << ", window " << o.pipeline.window << ", listening on "
              << (role == "backend" ? keyframe_topic_name(o.dds) : o.dds.depth_topic) << " (domain "
              << o.dds.domain_id << "), publishing " << o.dds.topic_prefix
              << (role == "frontend" ? "odom, " + keyframe_topic_name(o.dds) : "*") << '\n';
    if (role == "frontend") return run_frontend(o, participant);
    if (role == "backend") return run_backend(o, participant);
    return run_all(o, participant);
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::node_main(argc, argv);
}
