// A synthetic RGB-D sequence as a FrameSource: frames are ray-traced on demand, in memory, so any
// tool or test runs on generated data as on a TUM directory, with exact ground truth. The
// depth is not rounded to the PNG's 1 / depth_scale steps (0.2 mm) as a written sequence's is.
//
//   SyntheticSequenceOptions options;          // room_spheres, walk, 640x480, no noise
//   options.frames = 30;
//   options.noise = "range:1";
//   SyntheticSequence seq = make_synthetic_sequence(options);
//   Frame f = seq.load(3);                   // what a sensor would give
//   SyntheticFrame g = seq.render(3);        // the same frame with curvature, normals, pose
//   Trajectory gt = seq.ground_truth_trajectory();
#pragma once

#include <cstdint>
#include <string>

#include "jpcr/io/frame_source.hpp"
#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/io/synthetic_trajectory.hpp"

namespace jpcr {

class SyntheticSequence final : public FrameSource {
 public:
  /// Frame i is rendered at trajectory[i] with noise seeded by (seed, i). Throws InputError for
  /// an empty trajectory or a camera render() rejects.
  SyntheticSequence(SyntheticScene scene, const CameraIntrinsics& camera, Trajectory trajectory,
                    NoiseModel noise = {}, std::uint64_t seed = 0);

  std::size_t size() const override { return trajectory_.size(); }
  double timestamp(std::size_t index) const override { return trajectory_.at(index).timestamp; }
  Frame load(std::size_t index) const override { return render(index).frame; }
  std::optional<Eigen::Isometry3d> ground_truth(std::size_t index) const override {
    return trajectory_.at(index).pose;
  }
  const CameraIntrinsics& camera() const override { return camera_; }
  std::string description() const override;

  /// Frame `index` with its exact ground truth. Like load(), a pure function of the index:
  /// frames can be rendered in any order, also from several threads at once.
  SyntheticFrame render(std::size_t index) const;

  const SyntheticScene& scene() const { return scene_; }
  const Trajectory& trajectory() const { return trajectory_; }
  const NoiseModel& noise() const { return noise_; }
  std::uint64_t seed() const { return seed_; }

 private:
  SyntheticScene scene_;
  CameraIntrinsics camera_;
  Trajectory trajectory_;
  NoiseModel noise_;
  std::uint64_t seed_;
};

/// Everything jpcr_synth takes on its command line, with its defaults.
struct SyntheticSequenceOptions {
  std::string scene = "room_spheres";  // a scene name or a path to a scene .yaml
  TrajectoryKind trajectory = TrajectoryKind::kWalk;
  int frames = 100;
  std::string noise = "none";  // none | range:K | kinect
  int width = 640;             // px; the camera is synthetic_camera(width, height)
  int height = 480;
  std::uint64_t seed = 0;  // the walk and the noise
  TrajectoryParams trajectory_params;
  KinectNoiseParams kinect;
};

/// Loads the scene, makes the trajectory and parses the noise; throws InputError on bad input.
SyntheticSequence make_synthetic_sequence(const SyntheticSequenceOptions& options);

/// As above with the camera given (its size replaces options.width and height).
SyntheticSequence make_synthetic_sequence(const SyntheticSequenceOptions& options,
                                          const CameraIntrinsics& camera);

}  // namespace jpcr
