// bench_icp_peers: jpcr's ICP-ftf against OpenCV's cv::rgbd::ICPOdometry (opencv_contrib), frame
// to frame, depth only, on the same frames in one run (evaluation.md "Peers"). Frames are decoded
// before the clocks start; each method's time per frame covers its own preprocessing of the new
// frame (pyramid, normals) and the alignment to the previous one. The two methods alternate
// frame by frame, so load from other processes hits both alike.
//
//   bench_icp_peers [--dataset DIR] [--config CAM.yaml] [--frames N] [--params FILE.yaml]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>

#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "cli/arguments.hpp"
#include "jpcr/frontend/keyframe_tracker.hpp"
#include "jpcr/io/camera_yaml.hpp"
#include "jpcr/io/open_dataset.hpp"
#include "jpcr/io/trajectory_metrics.hpp"
#include "jpcr/io/tum_lists.hpp"
#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct MethodRun {
  std::string name;
  Trajectory trajectory;
  std::vector<double> ms;                    // per frame after the first
  int failures = 0;                          // frames whose alignment was not accepted
  double preprocess_ms = 0.0, icp_ms = 0.0;  // jpcr only: sums over the frames after the first
  int iterations = 0;
  std::map<std::string, int> verdicts;
};

// cv::rgbd::ICPOdometry with its defaults; each frame's cache (pyramids, normals) is built once,
// when it arrives, and reused when it is the reference of the next frame.
class OpenCvIcp {
 public:
  explicit OpenCvIcp(const CameraIntrinsics& c) {
    const cv::Mat K = (cv::Mat_<float>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    odometry_ = cv::makePtr<cv::rgbd::ICPOdometry>(K);
  }

  // Returns the motion T_prev,cur (maps current-frame points into the previous frame), or
  // nothing when OpenCV reports a failure.
  std::optional<Eigen::Isometry3d> track(const Frame& frame) {
    cv::Mat depth(frame.depth.height(), frame.depth.width(), CV_32FC1,
                  const_cast<float*>(frame.depth.data()));
    cv::Ptr<cv::rgbd::OdometryFrame> current =
        cv::rgbd::OdometryFrame::create(cv::Mat(), depth.clone());
    odometry_->prepareFrameCache(current, cv::rgbd::OdometryFrame::CACHE_ALL);
    std::optional<Eigen::Isometry3d> motion;
    if (previous_) {
      cv::Mat Rt;
      // dst_p = Rt src_p with src = current, dst = previous (OpenCV's convention).
      if (odometry_->compute(current, previous_, Rt)) {
        Eigen::Matrix4d M;
        for (int r = 0; r < 4; ++r)
          for (int k = 0; k < 4; ++k)
            M(r, k) = Rt.at<double>(r, k);
        motion = Eigen::Isometry3d(M);
      }
    }
    previous_ = current;
    return motion;
  }

 private:
  cv::Ptr<cv::rgbd::ICPOdometry> odometry_;
  cv::Ptr<cv::rgbd::OdometryFrame> previous_;
};

struct Metrics {
  double ate = 0.0, rpe_t = 0.0, rpe_r = 0.0, ms = 0.0, ms_median = 0.0;
};

// RPE per second (the TUM benchmark's unit), or per frame when the run spans less than a second
// (a few frames, e.g. tools/reproduce.sh --quick), where no one-second pair exists.
bool rpe_per_second(const Trajectory& estimate) {
  return estimate.size() > 1 && estimate.back().timestamp - estimate.front().timestamp >= 1.0;
}

Metrics evaluate(const Trajectory& gt, const MethodRun& run, bool per_second) {
  Metrics m;
  m.ate = compute_ate(gt, run.trajectory).translation.rmse;
  const RpeResult rpe = per_second ? compute_rpe(gt, run.trajectory, 1.0, DeltaUnit::kSeconds)
                                   : compute_rpe(gt, run.trajectory, 1.0, DeltaUnit::kFrames);
  m.rpe_t = rpe.translation.rmse;
  m.rpe_r = rpe.rotation.rmse;
  std::vector<double> ms = run.ms;
  double sum = 0.0;
  for (double t : ms)
    sum += t;
  m.ms = ms.empty() ? 0.0 : sum / ms.size();
  std::sort(ms.begin(), ms.end());
  m.ms_median = ms.empty() ? 0.0 : ms[ms.size() / 2];
  return m;
}

int run(int argc, char** argv) {
  cli::Arguments args("bench_icp_peers",
                      "Runs jpcr's ICP-ftf (KeyframeTracker, frame_to_frame) and OpenCV's\n"
                      "cv::rgbd::ICPOdometry (defaults) frame to frame on the same depth frames\n"
                      "and prints ATE, RPE per second and ms/frame for both, and their ratios.");
  args.option("dataset", "TUM RGB-D directory (or any --dataset of the jpcr tools)",
              "/work/shared/data/tum_fr1_xyz_first300")
      .option("config", "camera YAML", std::string(JPCR_SOURCE_DIR) + "/configs/tum_fr1.yaml")
      .option("params", "parameter YAML whose frontend: section configures jpcr")
      .option("frames", "number of frames to use (0 = all)", "0")
      .option("threads",
              "jpcr threads, the caller included (0 = one per core; default: the "
              "params' frontend.threads)")
      .flag("only-jpcr", "skip OpenCV (for tuning jpcr's parameters; no ratios)")
      .option("save", "write the trajectories to PREFIX_jpcr.txt and PREFIX_opencv.txt");
  return cli::run_program("bench_icp_peers", [&] {
    if (!args.parse(argc, argv)) return 0;
    FrontendParams params;
    if (args.has("params")) params = load_params(args.get("params")).frontend;
    params.tracker.mode = TrackingMode::frame_to_frame;
    if (args.has("threads")) params.threads = args.get_int("threads");
    const std::unique_ptr<FrameSource> source =
        open_dataset(args.get("dataset"), load_camera_yaml(args.get("config")));
    std::size_t frames = source->size();
    const int limit = args.get_int("frames");
    if (limit < 0) throw cli::UsageError("--frames must be >= 0");
    if (limit > 0) frames = std::min<std::size_t>(frames, limit);
    if (frames < 3) throw InputError(args.get("dataset") + ": fewer than 3 frames");
    const Trajectory gt = source->recorded_ground_truth(0, frames);
    const Eigen::Isometry3d start = source->ground_truth(0).value_or(Eigen::Isometry3d::Identity());
    KeyframeTracker tracker(params, start);
    const int jpcr_threads = tracker.threads();
    cv::setNumThreads(jpcr_threads);  // the same number of threads for both
    std::cerr << "bench_icp_peers: " << source->description() << ", using " << frames
              << " frames; jpcr threads " << jpcr_threads << ", OpenCV threads "
              << cv::getNumThreads() << '\n';

    const bool with_peer = !args.get_flag("only-jpcr");
    OpenCvIcp opencv(source->camera());
    MethodRun ours, peer;
    ours.name = "jpcr ICP-ftf";
    peer.name = "cv::rgbd::ICPOdometry";
    Eigen::Isometry3d peer_pose = start, peer_motion = Eigen::Isometry3d::Identity();
    for (std::size_t i = 0; i < frames; ++i) {
      const Frame frame = source->load(i);  // decoding is not timed
      const bool ours_first = i % 2 == 0;
      for (int turn = 0; turn < 2; ++turn) {
        const Clock::time_point t0 = Clock::now();
        if ((turn == 0) == ours_first) {
          const TrackResult r = tracker.track(frame);
          if (i > 0) ours.ms.push_back(ms_since(t0));
          ours.failures += r.kept_last_motion ? 1 : 0;
          if (i > 0) {
            ours.preprocess_ms += r.preprocess_ms;
            ours.icp_ms += r.icp_ms;
            ours.iterations += r.icp.iterations;
            ++ours.verdicts[to_string(r.icp.verdict)];
          }
          ours.trajectory.push_back(r.T_wc);
        } else if (with_peer) {
          const std::optional<Eigen::Isometry3d> motion = opencv.track(frame);
          if (i > 0) {
            peer.ms.push_back(ms_since(t0));
            if (motion)
              peer_motion = *motion;
            else
              ++peer.failures;  // keep the last motion, as jpcr does
            peer_pose = peer_pose * peer_motion;
          }
          peer.trajectory.push_back({frame.timestamp, peer_pose});
        }
      }
    }
    if (args.has("save")) {
      write_trajectory(args.get("save") + "_jpcr.txt", ours.trajectory, "jpcr ICP-ftf");
      if (with_peer)
        write_trajectory(args.get("save") + "_opencv.txt", peer.trajectory,
                         "cv::rgbd::ICPOdometry");
    }
    const bool per_second = rpe_per_second(ours.trajectory);
    const Metrics a = evaluate(gt, ours, per_second);
    const Metrics b = with_peer ? evaluate(gt, peer, per_second) : Metrics{};
    const char* unit = per_second ? "s" : "frame";
    std::printf("%zu frames of %s, %dx%d, depth only, frame to frame, %d threads\n\n", frames,
                args.get("dataset").c_str(), source->camera().width, source->camera().height,
                jpcr_threads);
    std::printf(
        "| method | ATE (m) | RPE (m/%s) | RPE (deg/%s) | ms/frame (mean) | ms/frame "
        "(median) | failed frames |\n|---|---|---|---|---|---|---|\n",
        unit, unit);
    for (const auto& [run, m] : {std::pair(&ours, a), std::pair(&peer, b)}) {
      if (run == &peer && !with_peer) continue;
      std::printf("| %s | %.4f | %.4f | %.3f | %.2f | %.2f | %d |\n", run->name.c_str(), m.ate,
                  m.rpe_t, m.rpe_r, m.ms, m.ms_median, run->failures);
    }
    if (with_peer)
      std::printf("| ratio jpcr / OpenCV | %.3f | %.3f | %.3f | %.3f | %.3f | |\n", a.ate / b.ate,
                  a.rpe_t / b.rpe_t, a.rpe_r / b.rpe_r, a.ms / b.ms, a.ms_median / b.ms_median);
    const double n = static_cast<double>(frames - 1);
    std::printf("\njpcr per frame: preprocessing %.2f ms, ICP %.2f ms (%.1f iterations)\n",
                ours.preprocess_ms / n, ours.icp_ms / n, ours.iterations / n);
    std::printf("jpcr verdicts:");
    for (const auto& [verdict, count] : ours.verdicts)
      std::printf(" %s %d", verdict.c_str(), count);
    std::printf("\n");
    if (with_peer)
      std::printf("speed-up of jpcr: %.2fx (mean), %.2fx (median)\n", b.ms / a.ms,
                  b.ms_median / a.ms_median);
    return 0;
  });
}

}  // namespace

}  // namespace jpcr

int main(int argc, char** argv) {
  return jpcr::run(argc, argv);
}
