// jpcr_synth: ray-traced synthetic RGB-D sequences with exact pose and curvature ground truth,
// written in the TUM layout (io/synthetic_writer.hpp).

#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "cli/arguments.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/number_format.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/io/synthetic_writer.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

// A bound against typing errors: a million frames is over 9 hours of a 30 Hz camera.
constexpr int kMaxFrames = 1000000;

std::string scene_list() {
  std::string list;
  for (const std::string& name : available_scenes())
    list += (list.empty() ? "" : ", ") + name;
  return list.empty() ? "(none found)" : list;
}

int run(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_synth",
      "Ray-traces a synthetic RGB-D sequence of an analytic scene (planes, spheres,\n"
      "cylinders, tori, boxes) and writes it in the TUM RGB-D layout with exact\n"
      "ground truth: depth/ (16-bit PNG at the camera's depth_scale, 5000/m by\n"
      "default), rgb/ (shaded by normal),\n"
      "depth.txt, rgb.txt, groundtruth.txt (exact camera-to-world poses),\n"
      "curvature/*.npy (float32 HxWx2, k1 >= k2 in 1/m, NaN where undefined),\n"
      "normals/*.npy (float32 HxWx3, camera axes) and camera.yaml.");
  args.option("scene", "scene name (configs/scenes/NAME.yaml) or a scene .yaml file",
              "room_spheres")
      .option("trajectory", "rail (10 mm per frame, translation only) | orbit | walk", "walk")
      .option("frames", "number of frames, 1..1000000", "100")
      .option("noise",
              "none | range:PCT (Gaussian along the ray, PCT % of the range, 0-100) | kinect",
              "none")
      .option("size",
              "image size WIDTHxHEIGHT; the camera is scaled to it, fx by the width's ratio and "
              "fy by the height's (another aspect ratio than the camera's gives non-square "
              "pixels; default: the camera's, 640x480)")
      .option("seed", "seed of the random walk and the noise (integer >= 0)", "0")
      .required("out", "output directory (created; must be empty unless --force)")
      .option("config", "camera YAML to render with (default: fx = fy = 550 at 640x480)")
      .option("params", "parameter YAML with a synthetic: section (default: built-in values)")
      .flag("force",
            "write into a non-empty output directory, replacing a sequence jpcr_synth wrote "
            "there (refused where it holds jpcr_run's or jpcr_curvature's results or a "
            "recorded dataset)")
      .epilog("scenes: " + scene_list() +
              "\n\nexample:\n  jpcr_synth --scene room_spheres --trajectory walk --frames 100 "
              "--noise range:1 --out out/room\n  jpcr_eval traj --gt out/room/groundtruth.txt "
              "--est out/room/groundtruth.txt");
  return cli::run_program("jpcr_synth", [&] {
    if (!args.parse(argc, argv)) return 0;
    SyntheticSequenceOptions options;
    options.scene = args.get("scene");
    try {
      options.trajectory = parse_trajectory_kind(args.get("trajectory"));
      options.noise = parse_noise(args.get("noise")).describe();
    } catch (const InputError& e) {
      throw cli::UsageError(e.what());
    }
    options.frames = args.get_int("frames");
    if (options.frames < 1 || options.frames > kMaxFrames)
      throw cli::UsageError("--frames must be in 1.." + std::to_string(kMaxFrames));
    const int seed = args.get_int("seed");
    if (seed < 0) throw cli::UsageError("--seed must be a non-negative integer");
    options.seed = static_cast<std::uint64_t>(seed);
    if (args.has("params")) {
      const Params params = load_params(args.get("params"));
      options.trajectory_params = params.synthetic.trajectory;
      options.kinect = params.synthetic.kinect;
    }
    CameraIntrinsics camera =
        args.has("config") ? load_camera_yaml(args.get("config")) : synthetic_camera();
    if (camera.has_distortion()) {  // a real camera's file, e.g. configs/tum_fr1.yaml
      throw InputError(args.get("config") +
                       ": distortion: the synthetic renderer is an ideal pinhole; give a camera "
                       "without distortion");
    }
    int width = camera.width, height = camera.height;
    if (args.has("size")) cli::parse_image_size("size", args.get("size"), width, height);
    if (width != camera.width || height != camera.height) camera = camera.resized(width, height);
    // The depth PNG holds depth in steps of 1/depth_scale up to 65535/depth_scale: a scale of 1
    // wrote 1 m steps under exact curvature ground truth, 1e6 an empty sequence (6.5 cm range).
    if (!(camera.depth_scale >= 1000.0 && camera.depth_scale <= 32767.0)) {
      throw InputError((args.has("config") ? args.get("config") : "camera") + ": depth_scale " +
                       format_double(camera.depth_scale) +
                       " per metre: a 16-bit depth PNG would hold steps of " +
                       format_double(1000.0 / camera.depth_scale) + " mm up to " +
                       format_double(65535.0 / camera.depth_scale) +
                       " m; jpcr_synth needs steps of 1 mm or finer and 2 m of range "
                       "(1000 <= depth_scale <= 32767)");
    }

    // --force replaces the entries written into OUT (depth/, curvature/, the lists, ...): an
    // input file inside OUT may be one of them, or inside one.
    if (args.get_flag("force")) {
      namespace fs = std::filesystem;
      std::error_code ec;
      const fs::path out = fs::weakly_canonical(fs::absolute(args.get("out"), ec), ec);
      for (const char* input : {"config", "params", "scene"}) {
        if (!args.has(input) || !fs::is_regular_file(args.get(input), ec)) continue;
        const fs::path inside =
            fs::weakly_canonical(fs::absolute(args.get(input), ec), ec).lexically_relative(out);
        if (!inside.empty() && *inside.begin() != "..")
          throw InputError(args.get(input) + ": --" + input + " lies in --out " + args.get("out") +
                           ", whose entries --force replaces (give another --out)");
      }
    }
    const Clock::time_point start = Clock::now();
    const SyntheticSequence sequence = make_synthetic_sequence(options, camera);
    std::cerr << "jpcr_synth: " << sequence.description() << ", trajectory "
              << to_string(options.trajectory) << '\n';
    std::ostringstream command;
    command << "jpcr_synth --scene " << options.scene << " --trajectory "
            << to_string(options.trajectory) << " --frames " << options.frames << " --noise "
            << options.noise << " --size " << width << 'x' << height << " --seed " << seed;
    // Both change the data (the rate, the rail's step, the walk, the Kinect model; the camera).
    if (args.has("params")) command << " --params " << args.get("params");
    if (args.has("config")) command << " --config " << args.get("config");
    SyntheticWriterOptions writer;
    writer.force = args.get_flag("force");
    writer.comment = command.str();
    cli::Progress progress("jpcr_synth", start);
    // Ctrl-C stops at the next frame and writes nothing (the writer's staging is removed).
    cli::install_stop_signal_handler(cli::OnStop::kSayItStops);
    writer.progress = [&](std::size_t done, std::size_t total) {
      cli::throw_if_stopped("frame " + std::to_string(done) + "; nothing written to " +
                            args.get("out"));
      progress(done, total);
    };
    const SyntheticWriteSummary written =
        write_synthetic_sequence(sequence, args.get("out"), writer);
    std::cout << "wrote " << sequence.size() << " frames to " << args.get("out") << " in "
              << std::chrono::duration<double>(Clock::now() - start).count() << " s\n";
    if (written.frames_without_depth > 0)
      std::cerr << "jpcr_synth: warning: " << written.frames_without_depth << " of "
                << written.frames
                << " frames hold no depth at all: nothing of the scene is in view within the "
                   "depth PNG's range of "
                << format_double(65535.0 / camera.depth_scale)
                << " m (check the scene's view and sizes)\n";
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run(argc, argv);
}
