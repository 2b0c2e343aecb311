// jpcr_curvature: dense principal curvatures of every frame of a dataset with Quad IT
// (method.md §3) or Quad LS (§4), written as .npy maps, colour PNGs with a key, optional PLY
// clouds and a JSON summary.
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "cli/arguments.hpp"
#include "cli/dataset_run_checks.hpp"
#include "cli/device_option.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/cuda/cpu_fallback_estimator.hpp"
#include "jpcr/cuda/curvature_estimator_factory.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/curvature_output.hpp"
#include "jpcr/io/json_writer.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/io/synthetic_writer.hpp"
#include "jpcr/quadric/least_squares_quadric.hpp"
#ifdef JPCR_HAVE_CGAL
#include "peers/cgal_jet_curvature.hpp"
#endif

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

struct FrameRecord {
  std::string stamp;  // the maps' file name: the timestamp to the microsecond (format_stamp)
  double timestamp = 0.0;
  QuadricMapSummary summary;
  double milliseconds = 0.0;
  std::string method;  // the estimator that made the map: the CPU's after a GPU failure
};

// Estimates a frame's map, and says with which estimator: a GPU Quad IT whose device failed
// (CpuFallbackEstimator) made it with the CPU one.
QuadricMap estimate(const CurvatureEstimator& estimator, const VertexMap& vertices,
                    std::string& method) {
  const auto* fallback = dynamic_cast<const CpuFallbackEstimator*>(&estimator);
  const int cpu_calls = fallback ? fallback->cpu_calls() : 0;
  QuadricMap map = estimator.estimate(vertices);
  method = fallback && fallback->cpu_calls() > cpu_calls ? fallback->cpu_name() : estimator.name();
  return map;
}

#ifdef JPCR_HAVE_CGAL
constexpr const char* kMethodHelp =
    "it (Quad IT) | ls (Quad LS) | jet (the peer: CGAL Monge jet fitting)";
#else
constexpr const char* kMethodHelp = "it (Quad IT) | ls (Quad LS)";
#endif

std::unique_ptr<CurvatureEstimator> make_estimator(const std::string& method,
                                                   const QuadricParams& params,
                                                   ComputeDevice device) {
  if (method == "it" || method == "quad-it")
    return make_curvature_estimator(device, params, std::cerr);
  if (method == "ls" || method == "quad-ls") return std::make_unique<LeastSquaresQuadric>(params);
#ifdef JPCR_HAVE_CGAL
  if (method == "jet" || method == "cgal-jet")
    return std::make_unique<peers::CgalJetCurvature>(params);
#else
  if (method == "jet" || method == "cgal-jet")
    throw cli::UsageError(
        "--method jet: this build has no CGAL (install libcgal-dev, reconfigure)");
#endif
  throw cli::UsageError(
      "--method must be 'it' (Quad IT), 'ls' (Quad LS) or 'jet' (CGAL jet "
      "fitting), got '" +
      method + "'");
}

void write_summary(const std::string& path, const std::string& dataset,
                   const CurvatureEstimator& estimator, const std::vector<FrameRecord>& frames) {
  write_file_atomically(path, [&](std::ostream& out) {
    JsonWriter json(out);
    long cpu_fallback_frames = 0;
    for (const FrameRecord& f : frames)
      cpu_fallback_frames += f.method != estimator.name() ? 1 : 0;
    json.begin_object()
        .field("dataset", dataset)
        .field("method", estimator.name())
        .field("cpu_fallback_frames", cpu_fallback_frames);  // the GPU's failed; see frames[]
    json.key("frames").begin_array();
    for (const FrameRecord& f : frames) {
      const QuadricMapSummary& s = f.summary;
      json.begin_object()
          .field("stamp", f.stamp)
          .field("timestamp", f.timestamp)
          .field("valid_fraction", s.pixels ? double(s.valid) / s.pixels : 0.0)
          .field("valid", s.valid)
          .field("no_depth", s.no_centre)
          .field("no_normal", s.no_normal)
          .field("too_few_samples", s.too_few_samples)
          .field("singular", s.singular)
          .field("no_step", s.no_step)
          .field("ms", f.milliseconds)
          .field("method", f.method)
          .end_object();
    }
    json.end_array().end_object();
    out << '\n';
  });
}

int run(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_curvature",
      "Estimates dense principal curvatures (k1 >= k2, 1/m; method.md sign: a ball\n"
      "seen from outside is negative) of every depth frame of a dataset, with Quad IT\n"
      "(the iterative weighted quadric fit) or Quad LS (the least-squares baseline).\n"
      "Writes OUT/curvature/<stamp>.npy (float32 HxWx2, NaN where invalid),\n"
      "OUT/curvature_png/<stamp>.png (colour with key), with Quad IT\n"
      "OUT/curvature_sd/<stamp>.npy (float32 HxW: each pixel's curvature sd in 1/m, from\n"
      "its fit's residuals; README \"Curvature spread\"), optionally OUT/ply/<stamp>.ply,\n"
      "and OUT/summary.json.");
  args.required("dataset", "TUM directory (jpcr_synth writes one) or MRPT .rawlog")
      .option("config", "camera YAML (default: the dataset's own camera.yaml or rawlog intrinsics)")
      .option("method", kMethodHelp, "it")
      .option("frames", "FIRST:LAST, 0-based, LAST excluded, or N for frame N alone (default: all)")
      .required("out",
                "output directory (created; an earlier run's maps there are replaced, other "
                "files are left alone; nothing is written when the run fails)")
      .option("params", "parameter YAML (section quadric:)", "")
      .option("color-scale", "curvedness drawn fully saturated in the PNG (1/m)", "10")
      .flag("ply", "also write a PLY point cloud per frame (k1, k2 as vertex properties)")
      .flag("no-sd",
            "write no curvature_sd/ maps with Quad IT (they take about as long as the fit)")
      .epilog(
          "example:\n  jpcr_synth --scene room_spheres --frames 5 --noise range:1 --out seq\n"
          "  jpcr_curvature --dataset seq --method it --out seq_it\n"
          "  jpcr_eval curvature --gt seq --est seq_it");
  cli::add_device_option(args, "Quad IT");
  return cli::run_program("jpcr_curvature", [&] {
    if (!args.parse(argc, argv)) return 0;
    const Params params = args.has("params") && !args.get("params").empty()
                              ? load_params(args.get("params"))
                              : Params{};
    const std::string method = args.get("method");
    const std::unique_ptr<CurvatureEstimator> estimator =
        make_estimator(method, params.quadric, cli::device_from(args, params));
    const bool is_quad_it = method == "it" || method == "quad-it";
    if (args.get_flag("no-sd") && !is_quad_it)
      std::cerr << "jpcr_curvature: warning: --no-sd has no effect: method " << method
                << " writes no sd maps (only Quad IT does)\n";
    if (args.has("device") && !is_quad_it)
      std::cerr << "jpcr_curvature: warning: --device has no effect: method " << method
                << " runs on the CPU (only Quad IT has a CUDA kernel)\n";
    CurvatureColorParams colors;
    colors.scale = static_cast<float>(args.get_double("color-scale"));
    if (!(colors.scale > 0.0f) || !std::isfinite(colors.scale))
      throw cli::UsageError("--color-scale must be a positive finite curvedness (1/m)");
    std::optional<CameraIntrinsics> camera;
    if (args.has("config")) camera = load_camera_yaml(args.get("config"));
    const std::unique_ptr<FrameSource> dataset =
        open_dataset(args.get("dataset"), camera, params.dataset);
    const cli::FrameRange range =
        cli::parse_frame_range(args.has("frames") ? args.get("frames") : "", dataset->size());
    cli::check_dataset_run(args, *dataset, params.quadric);
    cli::require_not_results_of(args, "report.json", "jpcr_run");
    // Written into a staging directory and moved into OUT at the end (io/staged_output.hpp).
    // Ctrl-C stops at the next frame, OUT unchanged; installed before the staging exists.
    cli::install_stop_signal_handler(cli::OnStop::kSayItStops);
    StagedOutput out(args.get("out"),
                     {"curvature", "curvature_sd", "curvature_png", "ply", "summary.json"});
    cli::require_inputs_apart_from(out, args);
    // The sd describes a weighted quadric fit (Quad IT's); Quad LS and the jet peer fit others.
    std::optional<QuadricParams> spread;
    if (is_quad_it && !args.get_flag("no-sd")) spread = params.quadric;
    const CurvatureWriter writer(out.directory(), args.get_flag("ply"), colors, spread);
    std::cerr << "jpcr_curvature: " << dataset->description() << ", " << estimator->name()
              << ", frames " << range.first << ":" << range.last << '\n';

    cli::Progress progress("jpcr_curvature");
    std::vector<FrameRecord> records;
    for (std::size_t i = range.first; i < range.last; ++i) {
      cli::throw_if_stopped("frame " + std::to_string(i) + "; " + out.target() +
                            " is left as it was");
      const Frame frame = dataset->load(i);
      const Clock::time_point t0 = Clock::now();
      const VertexMap vertices = compute_vertex_map(frame.depth, frame.camera);
      std::string method;
      const QuadricMap map = estimate(*estimator, vertices, method);
      FrameRecord record{format_stamp(frame.timestamp), frame.timestamp, summarize(map),
                         std::chrono::duration<double, std::milli>(Clock::now() - t0).count(),
                         method};
      if (record.summary.valid == 0) {
        std::cerr << "jpcr_curvature: warning: frame " << i << " (" << record.stamp
                  << "): no valid curvature (" << record.summary.no_centre << " of "
                  << record.summary.pixels << " pixels without depth)\n";
      }
      out.write([&] { writer.write(record.stamp, map, vertices); });
      std::ostringstream extra;
      extra.precision(3);
      extra << "valid " << 100.0 * record.summary.valid / record.summary.pixels << " %  "
            << record.milliseconds << " ms";
      records.push_back(record);
      progress(i - range.first + 1, range.last - range.first, extra.str());
    }
    out.write(
        [&] { write_summary(out.path("summary.json"), args.get("dataset"), *estimator, records); });
    // A signal during the last frame or the summary: said to stop, it stops before OUT changes.
    cli::throw_if_stopped("the end of the run; " + out.target() + " is left as it was");
    out.commit();
    std::cout << "wrote " << records.size() << " curvature maps to " << out.target() << '\n';
    if (const std::string warning = writer.sd_warning(); !warning.empty())
      std::cerr << "jpcr_curvature: warning: " << warning << '\n';
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run(argc, argv);
}
