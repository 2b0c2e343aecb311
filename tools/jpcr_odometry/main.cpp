// jpcr_odometry: the front end on a dataset. Dense point-to-plane ICP (ICP-ftf, the paper's
// baseline) frame to frame or frame to keyframe; writes the TUM trajectory and a JSON summary
// with every frame's verdict, timings and the keyframes.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cli/arguments.hpp"
#include "cli/progress.hpp"
#include "cli/stop_signal.hpp"
#include "jpcr/frontend/keyframe_tracker.hpp"
#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/json_writer.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/io/params.hpp"
#include "jpcr/io/staged_output.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

struct Run {
  std::string dataset, description, mode;
  int threads = 1;
  double seconds = 0.0;
  std::vector<TrackResult> frames;
  std::vector<int> keyframes;
};

// What a run killed outright (SIGKILL) left beside `file` (below): FILE.partial-PID, its new
// file never moved in, and FILE.previous-PID, the earlier file's second name or the earlier file
// moved aside, of a PID that is gone. A previous copy goes back when FILE is missing (killed
// between moving it aside and moving the new one in); the rest is removed. Best effort.
void clean_up_after_killed_runs(const std::string& file) {
  namespace fs = std::filesystem;
  const fs::path target(file);
  const std::string name = target.filename().string();
  std::error_code ec;
  fs::directory_iterator it(target.has_parent_path() ? target.parent_path() : fs::path("."), ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string entry = it->path().filename().string();
    for (const std::string tag : {".partial-", ".previous-"}) {
      const long pid = owner_pid(entry, name + tag);
      if (pid == 0 || !process_is_gone(pid)) continue;
      std::error_code ignored;
      if (tag == ".previous-" && !fs::exists(fs::symlink_status(target, ignored)))
        fs::rename(it->path(), target, ignored);
      else
        fs::remove(it->path(), ignored);
    }
  }
}

// Makes the missing parent directories of `files` and returns them, deepest first, for a run
// that fails later to remove; when one cannot be made, removes those it made before throwing,
// so a failed run leaves no empty directory behind.
std::vector<std::filesystem::path> make_parents(const std::vector<std::string>& files) {
  namespace fs = std::filesystem;
  std::vector<fs::path> made;
  const auto deepest_first = [&] {
    std::sort(made.begin(), made.end(), [](const fs::path& a, const fs::path& b) {
      return a.string().size() > b.string().size();
    });
  };
  try {
    for (const std::string& file : files) {
      std::error_code ec;
      for (fs::path p = fs::path(file).parent_path(); !p.empty() && !fs::exists(p, ec);
           p = p.parent_path())
        made.push_back(p);
      const std::string parent = fs::path(file).parent_path().string();
      if (!parent.empty()) ensure_directory(parent);
    }
  } catch (...) {
    deepest_first();
    std::error_code ec;
    for (const fs::path& p : made)
      fs::remove(p, ec);  // empty ones only
    throw;
  }
  deepest_first();
  return made;
}

void write_summary(std::ostream& out, const Run& run) {
  std::map<std::string, int> verdicts;
  int kept = 0;
  double preprocess = 0.0, icp = 0.0;
  for (const TrackResult& r : run.frames) {
    if (!r.is_gauge) ++verdicts[to_string(r.icp.verdict)];
    kept += r.kept_last_motion ? 1 : 0;
    preprocess += r.preprocess_ms;
    icp += r.icp_ms;
  }
  const double n = static_cast<double>(std::max<std::size_t>(run.frames.size(), 1));
  JsonWriter json(out);
  json.begin_object();
  json.field("program", "jpcr_odometry").field("dataset", run.dataset);
  json.field("description", run.description).field("mode", run.mode);
  json.field("threads", run.threads).field("frames", run.frames.size());
  json.key("timing").begin_object();
  json.field("total_s", run.seconds).field("ms_per_frame", 1e3 * run.seconds / n);
  json.field("preprocess_ms_mean", preprocess / n).field("icp_ms_mean", icp / n);
  json.end_object();
  json.key("verdicts").begin_object();
  for (const char* v : {"ok", "degenerate", "diverged", "too_few_points"})
    json.field(v, verdicts[v]);
  json.end_object();
  json.field("kept_last_motion", kept);
  json.key("keyframes").begin_array();
  for (int k : run.keyframes)
    json.value(k);
  json.end_array();
  json.key("per_frame").begin_array();
  for (const TrackResult& r : run.frames) {
    json.begin_object();
    json.field("index", r.index).field("timestamp", r.T_wc.timestamp);
    json.field("reference", r.reference);
    json.field("verdict", r.is_gauge ? "first" : to_string(r.icp.verdict));  // first with points
    json.field("iterations", r.icp.iterations).field("converged", r.icp.converged);
    json.field("rms_m", r.icp.rms).field("inlier_ratio", r.icp.inlier_ratio);
    json.field("degeneracy", r.icp.degeneracy).field("overlap", r.overlap);
    json.field("is_keyframe", r.is_keyframe).field("kept_last_motion", r.kept_last_motion);
    json.field("preprocess_ms", r.preprocess_ms).field("icp_ms", r.icp_ms);
    json.end_object();
  }
  json.end_array();
  json.end_object();
  out << '\n';
}

int run(int argc, char** argv) {
  cli::Arguments args(
      "jpcr_odometry",
      "Tracks a depth sequence with jpcr's front end: dense projective point-to-plane ICP\n"
      "(ICP-ftf), coarse to fine over a 3-level pyramid, with robust and depth weights, and a\n"
      "keyframe policy. Writes the camera-to-world trajectory (TUM format, first pose =\n"
      "identity) and a JSON summary: every frame's verdict (ok, degenerate, diverged,\n"
      "too_few_points), iterations, RMS, inlier ratio, degeneracy and timings, and the\n"
      "keyframes. A frame whose alignment fails keeps the last good motion and is counted in\n"
      "kept_last_motion.");
  args.required("dataset", "TUM RGB-D directory (depth.txt) or MRPT .rawlog file")
      .required("out", "trajectory file to write (TUM: timestamp tx ty tz qx qy qz qw)")
      .option("config", "camera YAML, e.g. configs/tum_fr1.yaml (default: the dataset's own)")
      .option("params",
              "parameter YAML with a frontend: section (default: built-in values, "
              "as in configs/default.yaml)")
      .option("mode", "frame_to_frame (ICP-ftf) | frame_to_keyframe (default: the params')")
      .option("summary", "JSON summary to write (default: OUT.json)")
      .option("frames",
              "use only the first N frames (0 = all); a count, unlike jpcr_run's FIRST:LAST", "0")
      .option("threads", "threads, the caller included (0 = one per core; default: the params')")
      .epilog(
          "example:\n  jpcr_odometry --dataset ../shared/data/tum_fr1_xyz_first300 "
          "--config configs/tum_fr1.yaml --out out/icp.txt\n"
          "  jpcr_eval traj --gt ../shared/data/tum_fr1_xyz_first300/groundtruth.txt --est "
          "out/icp.txt");
  return cli::run_program("jpcr_odometry", [&] {
    if (!args.parse(argc, argv)) return 0;
    Params params;
    if (args.has("params")) params = load_params(args.get("params"));
    FrontendParams& fp = params.frontend;
    if (args.has("mode")) {
      try {
        fp.tracker.mode = parse_tracking_mode(args.get("mode"));
      } catch (const InputError& e) {
        throw cli::UsageError(std::string("--mode: ") + e.what());
      }
    }
    if (args.has("threads")) {
      fp.threads = args.get_int("threads");
      if (fp.threads < 0 || fp.threads > 256)
        throw cli::UsageError("--threads must be in 0..256 (0: one per core)");
    }
    const int limit = args.get_int("frames");
    if (limit < 0) throw cli::UsageError("--frames must be >= 0");
    // The files replaced: the paths given, or the regular files links lead to (a device, a pipe
    // or a link to nothing is refused here, before the run: see output_file_target).
    const std::string out = output_file_target(args.get("out"));
    const std::string summary =
        output_file_target(args.has("summary") ? args.get("summary") : args.get("out") + ".json");
    for (const std::string& file : {out, summary})
      clean_up_after_killed_runs(file);
    // Before the run, so it fails early. Absolute first: weakly_canonical leaves a relative path
    // that does not exist yet relative, so "o.txt" and "./o.txt" compared unequal.
    // A path that cannot be resolved (a link loop) gives an empty one: compare it as written,
    // and let the write say what is wrong with it.
    const auto resolved = [](const std::string& file) {
      std::error_code ec;
      const std::filesystem::path absolute = std::filesystem::absolute(file, ec);
      const std::filesystem::path canonical = std::filesystem::weakly_canonical(absolute, ec);
      return ec ? absolute.lexically_normal() : canonical;
    };
    if (resolved(out) == resolved(summary))
      throw cli::UsageError("--summary and --out name the same file: " + out);
    for (const std::string& file : {out, summary}) {
      require_output_file_apart_from(file, args.get("dataset"), "--dataset");
      for (const char* input : {"config", "params"})
        if (args.has(input))
          require_output_file_apart_from(file, args.get(input), std::string("--") + input);
      require_not_dataset_or_results_file(file);
      const std::filesystem::path name = std::filesystem::path(file).filename();
      if (std::filesystem::is_directory(file) || name.empty() || name == "." || name == "..")
        throw InputError(file + ": names a directory, not a file to write");
      // The nearest existing parent must be a directory, or no run could write there.
      for (std::filesystem::path p = std::filesystem::path(file).parent_path(); !p.empty();
           p = p.parent_path()) {
        std::error_code ec;
        if (!std::filesystem::exists(p, ec)) continue;
        if (!std::filesystem::is_directory(p, ec))
          throw InputError(file + ": " + p.string() + " is not a directory");
        if (::access(p.c_str(), W_OK | X_OK) != 0)
          throw InputError(file + ": cannot write in " + p.string());
        break;
      }
    }
    std::optional<CameraIntrinsics> camera;
    if (args.has("config")) camera = load_camera_yaml(args.get("config"));
    const std::string dataset = args.get("dataset");
    const std::unique_ptr<FrameSource> source = open_dataset(dataset, camera, params.dataset);
    std::size_t frames = source->size();
    if (limit > 0 && static_cast<std::size_t>(limit) > frames)
      std::cerr << "warning: --frames " << limit << ": the dataset has " << frames
                << " frames; running them all\n";
    if (limit > 0) frames = std::min<std::size_t>(frames, limit);
    if (frames == 0) throw InputError(dataset + ": no frames");

    KeyframeTracker tracker(fp);
    Run run;
    run.dataset = dataset;
    run.description = source->description();
    run.mode = to_string(fp.tracker.mode);
    run.threads = tracker.threads();
    std::cerr << "jpcr_odometry: " << run.description << ", " << run.mode << ", " << run.threads
              << " threads\n";
    const Clock::time_point start = Clock::now();
    cli::Progress progress("jpcr_odometry", start);
    Trajectory trajectory;
    std::size_t failed = 0;
    // Ctrl-C stops at the next frame, nothing written
    cli::install_stop_signal_handler(cli::OnStop::kSayItStops);
    for (std::size_t i = 0; i < frames; ++i) {
      cli::throw_if_stopped("frame " + std::to_string(i) + "; nothing written");
      const Frame frame = source->load(i);
      TrackResult r;
      try {
        r = tracker.track(frame);
      } catch (const InputError& e) {
        throw InputError(dataset + ": frame " + std::to_string(i) + ": " + e.what());
      }
      failed += r.kept_last_motion ? 1 : 0;
      trajectory.push_back(r.T_wc);
      run.frames.push_back(r);
      progress(i + 1, frames,
               std::to_string(tracker.keyframe_indices().size()) + " keyframes  " +
                   std::to_string(failed) + " failed");
    }
    // A signal during the last frame: said to stop, it stops (nothing written).
    cli::throw_if_stopped("the end of the run; nothing written");
    run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    run.keyframes = tracker.keyframe_indices();
    // Missing parent directories are made only now, so a run that fails creates nothing.
    const std::vector<std::filesystem::path> made = make_parents({out, summary});
    // Both files or neither: each is written beside its target first; then the new files move
    // in, and when one cannot, the earlier trajectory comes back, so both targets are as they
    // were.
    const std::string pid = std::to_string(::getpid());
    const std::string staged = out + ".partial-" + pid,
                      staged_summary = summary + ".partial-" + pid,
                      previous = out + ".previous-" + pid;
    std::error_code ec;
    const bool had_out = std::filesystem::exists(std::filesystem::symlink_status(out, ec));
    const auto clean_up = [&] {
      std::remove(staged.c_str());
      std::remove(staged_summary.c_str());
      for (const std::filesystem::path& p : made)
        std::filesystem::remove(p, ec);  // empty ones only
    };
    const auto fail = [&](const std::string& file, const std::string& why) {
      clean_up();
      return InputError(file + ": cannot be moved into place (" + why + ")");
    };
    try {
      write_trajectory(staged, trajectory, "jpcr_odometry " + run.mode + " on " + dataset);
      write_file_atomically(staged_summary, [&](std::ostream& s) { write_summary(s, run); });
    } catch (const InputError& e) {
      clean_up();
      // Named by the files asked for, not by their staged copies (gone when the user reads it).
      std::string why = e.what();
      for (const auto& [from, to] : {std::pair{staged, out}, std::pair{staged_summary, summary}})
        if (why.rfind(from + ":", 0) == 0) why = to + why.substr(from.size());
      throw InputError(why + " (nothing written)");
    } catch (...) {
      clean_up();
      throw;
    }
    // The earlier trajectory gets a second name (a hard link), so OUT never goes missing; where
    // links are not possible it is moved aside instead.
    if (had_out) {
      std::remove(previous.c_str());
      if (::link(out.c_str(), previous.c_str()) != 0 &&
          std::rename(out.c_str(), previous.c_str()) != 0)
        throw fail(out, std::strerror(errno));
    }
    const auto put_back = [&](const std::string& why) {
      if (had_out && std::rename(previous.c_str(), out.c_str()) != 0)
        return why + "; the earlier " + out + " is kept as " + previous;
      if (!had_out) std::remove(out.c_str());
      return why;
    };
    for (const auto& [from, to] : {std::pair{staged, out}, std::pair{staged_summary, summary}})
      if (std::rename(from.c_str(), to.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        throw fail(to, put_back(why));
      }
    if (had_out) std::remove(previous.c_str());
    std::cout << "wrote " << trajectory.size() << " poses to " << out << " and the summary to "
              << summary << " (" << run.keyframes.size() << " keyframes, " << failed
              << " frames kept the last motion, " << 1e3 * run.seconds / static_cast<double>(frames)
              << " ms/frame)\n";
    if (failed > 0)
      std::cerr << "warning: " << failed << " of " << frames
                << " frames kept the last motion (their alignment failed): their poses are not "
                   "trusted\n";
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run(argc, argv);
}
