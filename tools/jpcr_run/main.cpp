// jpcr_run: the full system on a dataset — the ICP-ftf front end with keyframes, J-ftf per
// keyframe pair, J-full per window (backend/keyframe_pipeline.hpp) — or one of the paper's
// methods alone for comparisons. Writes the refined trajectory, the keyframes, a curvature map
// per keyframe and a JSON report; with ground truth, prints the error table.
#include <chrono>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>

#include "cli/arguments.hpp"
#include "cli/dataset_run_checks.hpp"
#include "cli/device_option.hpp"
#include "cli/heartbeat.hpp"
#include "cli/pipeline_options.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/cuda/refiner_factory.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/curvature_output.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/io/synthetic_writer.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr_run/run_report.hpp"
#ifdef JPCR_HAVE_DDS
#include "cli/dds_options.hpp"
#include "cli/pipeline_publisher.hpp"
#endif

namespace jpcr {

namespace {

// How often a frame that is still being refined says so (cli::Heartbeat).
constexpr std::chrono::seconds kHeartbeat{10};

// A write into OUT that failed (a full disk): passed on as it is, not blamed on the dataset.
struct OutputError : InputError {
  using InputError::InputError;
};

Trajectory keyframe_trajectory(const KeyframePipeline& p) {
  Trajectory out;
  for (const PipelineKeyframe& k : p.keyframes())
    out.push_back(k.refined);
  return out;
}

int run_main(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_run",
      "Runs jpcr on a depth dataset: the ICP-ftf front end picks keyframes, J-ftf refines\n"
      "each keyframe against the previous one jointly with per-pixel quadrics, J-full refines\n"
      "windows of keyframes, and every frame is re-anchored to its refined keyframe\n"
      "(--method pipeline). The paper's methods also run alone, on every consecutive frame:\n"
      "icp-ftf, j-ftf, j-full, q-full and icp-bundle (the point-to-plane bundle adjustment\n"
      "baseline over the same sliding windows as j-full, solved with Ceres; section icp_bundle\n"
      "of --params). Writes OUT/trajectory.txt (TUM, refined),\n"
      "OUT/front_end.txt (ICP-ftf), OUT/keyframes.txt, OUT/curvature/<stamp>.npy,\n"
      "OUT/curvature_sd/<stamp>.npy (each pixel's curvature sd, 1/m, from its fit's residuals)\n"
      "and OUT/curvature_png/<stamp>.png per keyframe, OUT/report.json, and OUT/verdicts.txt\n"
      "(per frame: front-end and back-end verdicts, trusted yes/no). A keyframe's map comes\n"
      "from the quadrics of its J-ftf pair or, for the first keyframe of a J-full window, of\n"
      "J-full; elsewhere it is Quad IT's. report.json keyframe_records[].curvature says whose.");
  args.required("dataset", "TUM directory (jpcr_synth writes one) or MRPT .rawlog")
      .option("config", "camera YAML (default: the dataset's camera.yaml or rawlog intrinsics)")
      .option("method",
              "pipeline | icp-ftf | j-ftf | j-full | q-full | icp-bundle (default: --params' "
              "pipeline.method, built in: pipeline)")
      .option("window",
              "keyframes per J-full / Q-full / ICP-bundle window, 2-16 (default: --params' "
              "pipeline.window, built in: 5)")
      .option("params", "parameter YAML (sections frontend, quadric, joint, icp_bundle, pipeline)")
      .option("frames", "FIRST:LAST, 0-based, LAST excluded, or N for frame N alone (default: all)")
      .required("out",
                "output directory (created; the outputs of an earlier run there are replaced, "
                "other files are left alone; nothing is written when the run fails)")
      .flag("ply", "also write a PLY point cloud per keyframe")
      .flag("no-sd",
            "write no curvature_sd/ maps and, with --dds, publish none (each takes about as long "
            "as a Quad IT fit)");
  cli::add_device_option(args);
#ifdef JPCR_HAVE_DDS
  args.flag("dds",
            "also publish odom, keyframe_pose, curvature, curvature_color, curvature_sd and path"
            " over DDS"
            " (as jpcr_node does; --params' dds: section, --domain, --cyclone-uri)");
  args.option("domain", "DDS domain id 0..232 with --dds (overrides dds.domain_id)")
      .option("cyclone-uri", "Cyclone DDS configuration with --dds, file://PATH or XML")
      .option("wait-readers",
              "with --dds, before the first frame wait until N readers are matched, counted over "
              "the topics (one per topic each process reads): a volatile reader matched late "
              "misses the first samples; a transient-local one gets what each topic keeps "
              "(default 0: no wait)")
      .option("wait-timeout",
              "seconds --wait-readers waits at most, then the run goes on (default 10)");
#endif
  args.epilog(
      "example (60 frames of the walk travel far enough for two keyframes):\n"
      "  jpcr_synth --scene room_spheres --frames 60 --size 320x240 --noise range:1 --out seq\n"
      "  jpcr_run --dataset seq --out seq_run\n"
      "  jpcr_eval traj --gt seq/groundtruth.txt --est seq_run/trajectory.txt");
  return cli::run_program("jpcr_run", [&] {
    if (!args.parse(argc, argv)) return 0;
    Params params;
    PipelineParams pipeline = cli::pipeline_params_from(args, &params);
    // Options that change nothing for the method are said, not silently taken (scripts may pass
    // one set of options to every method, as tools/reproduce.sh does).
    const bool pairs_only = !refines_windows(pipeline.method);
    if (args.has("window") && pairs_only)
      std::cerr << "jpcr_run: warning: --window has no effect: method "
                << to_string(pipeline.method) << " refines no windows\n";
    for (const char* flag : {"ply", "no-sd"})
      if (args.get_flag(flag) && pipeline.method == PipelineMethod::kIcpFtf)
        std::cerr << "jpcr_run: warning: --" << flag
                  << " has no effect: method icp-ftf fits no quadrics\n";
    if (!pipeline.keep_history)
      throw InputError(args.get("params") +
                       ": pipeline.keep_history: false is for live runs (jpcr_node); jpcr_run "
                       "writes every frame's pose and needs true");
    // Every option is checked before the dataset is opened (a rawlog's first read takes long).
    const ComputeDevice device = cli::device_from(args, params);
    const bool has_j_ftf = pipeline.method == PipelineMethod::kJointFtf ||
                           pipeline.method == PipelineMethod::kPipeline;
    if (args.has("device") && !has_j_ftf)
      std::cerr << "jpcr_run: warning: --device has no effect: method "
                << to_string(pipeline.method)
                << " runs on the CPU (only J-ftf has a CUDA kernel; the keyframes' Quad IT maps "
                   "are fitted on the CPU)\n";
#ifdef JPCR_HAVE_DDS
    for (const char* option : {"domain", "cyclone-uri", "wait-readers", "wait-timeout"})
      if (!args.get_flag("dds") && args.has(option))
        throw cli::UsageError(std::string("--") + option + " needs --dds");
    const int wait_readers = args.has("wait-readers") ? args.get_int("wait-readers") : 0;
    if (wait_readers < 0 || wait_readers > 1000)
      throw cli::UsageError("--wait-readers must be 0..1000");
    const double wait_timeout = args.has("wait-timeout") ? args.get_double("wait-timeout") : 10.0;
    if (!(wait_timeout >= 0.0 && wait_timeout <= 86400.0))
      throw cli::UsageError("--wait-timeout must be 0..86400 s");
    if (args.has("wait-timeout") && wait_readers == 0)
      std::cerr << "jpcr_run: warning: --wait-timeout has no effect without --wait-readers\n";
#endif
    std::optional<CameraIntrinsics> camera;
    if (args.has("config")) camera = load_camera_yaml(args.get("config"));
    const std::unique_ptr<FrameSource> dataset =
        open_dataset(args.get("dataset"), camera, params.dataset);
    const cli::FrameRange range =
        cli::parse_frame_range(args.has("frames") ? args.get("frames") : "", dataset->size());
    std::cerr << "jpcr_run: " << dataset->description() << ", method " << to_string(pipeline.method)
              << ", window " << pipeline.window << ", frames " << range.first << ":" << range.last
              << '\n';

#ifdef JPCR_HAVE_DDS
    std::optional<DdsParticipant> participant;
    std::optional<cli::PipelinePublisher> dds;
    if (args.get_flag("dds")) {
      const DdsConfig config = cli::dds_config_from(args);
      participant.emplace(config);
      dds.emplace(*participant, config, pipeline.keep_history);
    }
#endif
    const KeyframePipeline* self = nullptr;
    const RefinerFactory refiners = device_refiner_factory(device, std::cerr);
    // ICP-ftf fits no quadrics: a width the pattern cannot take is no reason to refuse it.
    cli::check_dataset_run(args, *dataset, pipeline.joint.quadric,
                           pipeline.method != PipelineMethod::kIcpFtf);
    cli::require_not_results_of(args, "summary.json", "jpcr_curvature");
    // Everything is written into a staging directory and moved into OUT at the end: a run that
    // fails leaves OUT as it was, and a run into an earlier run's OUT replaces all its outputs.
    // Ctrl-C or SIGTERM stops the run at the next frame; OUT is left as it was. Installed
    // before the staging directory exists, so that a signal from here on removes it.
    cli::install_stop_signal_handler(cli::OnStop::kSayItStops);
    StagedOutput out(args.get("out"),
                     {"trajectory.txt", "verdicts.txt", "front_end.txt", "keyframes.txt",
                      "report.json", "curvature", "curvature_sd", "curvature_png", "ply"});
    cli::require_inputs_apart_from(out, args);
    std::optional<QuadricParams> spread;  // the pattern and fit every keyframe map was made with
    if (!args.get_flag("no-sd")) spread = pipeline.joint.quadric;
    const CurvatureWriter writer(out.directory(), args.get_flag("ply"), {}, spread);
    KeyframePipeline runner(
        pipeline,
        [&](int k, const Frame& frame, const QuadricMap& quadrics) {
          // The vertex map (of the depth the map was fitted on) is needed for the sd and the PLY;
          // compute_vertex_map is cheap next to J-ftf.
          Image<float> sd;              // the one written, published too (--dds)
          out.write<OutputError>([&] {  // e.g. a full disk: named by OUT, not by the dataset
            sd = writer.write(format_stamp(frame.timestamp), quadrics,
                              compute_vertex_map(frame.depth, frame.camera));
          });
#ifdef JPCR_HAVE_DDS
          if (dds) dds->keyframe_final(*self, k, frame, quadrics, sd);
#endif
          (void)k;
          (void)self;
        },
        refiners);
    self = &runner;
    const std::string unchanged = "; " + out.target() + " is left as it was";
#ifdef JPCR_HAVE_DDS
    if (dds && wait_readers > 0) {
      std::cerr << "jpcr_run: waiting up to " << wait_timeout << " s for DDS readers ("
                << wait_readers << " wanted)\n";
      const auto timeout = std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000.0));
      if (!dds->wait_for_readers(wait_readers, timeout, [] { return !cli::stop_requested(); }) &&
          !cli::stop_requested())
        std::cerr << "jpcr_run: " << dds->matched_readers() << " of " << wait_readers
                  << " DDS readers matched; publishing anyway\n";
    }
#endif
    cli::Progress progress("jpcr_run");
    // A frame that completes a J-full window takes tens of seconds at 640x480 on the CPU.
    const auto say = [&progress](const std::string& line) { progress.note(line); };
    for (std::size_t i = range.first; i < range.last; ++i) {
      cli::throw_if_stopped("frame " + std::to_string(i) + unchanged);
      const PipelineFrame& f = [&]() -> const PipelineFrame& {
        const cli::Heartbeat heartbeat("frame " + std::to_string(i), kHeartbeat, say);
        try {
          return runner.add(dataset->load(i));
        } catch (const OutputError&) {  // the output's fault, not the dataset's
          throw;
        } catch (const InputError& e) {  // name the dataset and the frame
          throw InputError(args.get("dataset") + ": frame " + std::to_string(i) + ": " + e.what());
        }
      }();
#ifdef JPCR_HAVE_DDS
      if (dds) dds->frame_added(runner, f);
#endif
      // None before the first frame with points (a sensor that starts blank).
      if (!runner.keyframes().empty()) {
        const PipelineKeyframe& k = runner.keyframes().back();
        for (const std::optional<RefinementReport>* r : {&k.pair, &k.window})
          if (k.frame == f.index && *r && (*r)->verdict == RefinementVerdict::kError)
            progress.note("frame " + std::to_string(i) + ": " + (*r)->method + " failed (" +
                          (*r)->error + "); the front end's motion is kept");
      }
      std::ostringstream extra;
      extra << "keyframes " << runner.keyframes().size() << "  icp " << to_string(f.icp_verdict)
            << (f.kept_last_motion ? " (kept last motion)" : "");
      progress(i - range.first + 1, range.last - range.first, extra.str());
    }
    // finish() refines the last, partial window: its failure is said as the loop's are.
    const bool no_keyframe = runner.keyframes().empty();  // no frame had points
    const bool window_before = !no_keyframe && runner.keyframes().back().window.has_value();
    if (!pairs_only) progress.note("finishing: the last, partial window (if any) is refined");
    {
      const cli::Heartbeat heartbeat("finishing", kHeartbeat, say);
      runner.finish();
    }
    if (no_keyframe) {
      progress.note(
          "no frame had the points to be aligned against: every pose is the first's, "
          "untrusted");
    } else if (const PipelineKeyframe& k = runner.keyframes().back();
               !window_before && k.window && k.window->verdict == RefinementVerdict::kError) {
      progress.note("frame " + std::to_string(k.frame) + ": " + k.window->method + " failed (" +
                    k.window->error + ") on the last window; its poses are not applied");
    }
    cli::throw_if_stopped("the end of the run" + unchanged);
#ifdef JPCR_HAVE_DDS
    if (dds) {
      dds->finished(runner);
      if (!dds->flush(std::chrono::seconds(5)))
        std::cerr << "jpcr_run: not every DDS reader acknowledged the last samples\n";
    }
#endif

    const Trajectory refined = runner.trajectory();
    // As recorded (TUM: groundtruth.txt), so that report.json's numbers are jpcr_eval's.
    const Trajectory gt = dataset->recorded_ground_truth(range.first, range.last);
    const auto front_errors = run::evaluate(gt, runner.front_end_trajectory());
    const auto errors = run::evaluate(gt, refined);
    out.write([&] {
      write_trajectory(out.path("trajectory.txt"), refined);
      write_file_atomically(out.path("verdicts.txt"),
                            [&](std::ostream& o) { run::write_verdicts(o, runner); });
      write_trajectory(out.path("front_end.txt"), runner.front_end_trajectory());
      write_trajectory(out.path("keyframes.txt"), keyframe_trajectory(runner));
      write_file_atomically(out.path("report.json"), [&](std::ostream& o) {
        const run::RunInputs inputs{
            args.get("dataset"), range.first, args.has("config") ? args.get("config") : "",
            args.has("params") ? args.get("params") : "", to_string(device)};
        run::write_report(o, inputs, runner, front_errors, errors, progress.seconds());
      });
    });
    cli::throw_if_stopped("writing the outputs" + unchanged);  // a signal since the last check
    out.commit();
    std::cout << "wrote " << refined.size() << " poses, " << runner.keyframes().size()
              << " keyframes and " << writer.written() << " curvature maps to " << out.target()
              << '\n';
    if (const std::string warning = run::untrusted_warning(runner); !warning.empty())
      std::cerr << "jpcr_run: warning: " << warning << '\n';
    if (const std::string warning = writer.sd_warning(); !warning.empty())
      std::cerr << "jpcr_run: warning: " << warning << '\n';
    if (errors)
      run::print_error_table(std::cout, to_string(pipeline.method), front_errors, errors, runner);
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run_main(argc, argv);
}
