#include "jpcr/io/synthetic_sequence.hpp"

#include <utility>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

SyntheticSequence::SyntheticSequence(SyntheticScene scene, const CameraIntrinsics& camera,
                                     Trajectory trajectory, NoiseModel noise, std::uint64_t seed)
    : scene_(std::move(scene)),
      camera_(camera),
      trajectory_(std::move(trajectory)),
      noise_(std::move(noise)),
      seed_(seed) {
  if (trajectory_.empty()) throw InputError("a synthetic sequence needs at least one pose");
  check_synthetic_camera(camera_);
  check_cameras_outside_solids(scene_, trajectory_);
}

std::string SyntheticSequence::description() const {
  return "synthetic scene " + scene_.name + ": " + std::to_string(trajectory_.size()) +
         " frames at " + std::to_string(camera_.width) + "x" + std::to_string(camera_.height) +
         ", noise " + noise_.describe() + ", seed " + std::to_string(seed_);
}

SyntheticFrame SyntheticSequence::render(std::size_t index) const {
  const StampedPose& pose = trajectory_.at(index);
  return jpcr::render(scene_, camera_, pose.pose, noise_, seed_, index, pose.timestamp);
}

SyntheticSequence make_synthetic_sequence(const SyntheticSequenceOptions& options) {
  if (options.width < 1 || options.height < 1) {
    throw InputError("synthetic image size must be positive, got " + std::to_string(options.width) +
                     "x" + std::to_string(options.height));
  }
  return make_synthetic_sequence(options, synthetic_camera(options.width, options.height));
}

SyntheticSequence make_synthetic_sequence(const SyntheticSequenceOptions& options,
                                          const CameraIntrinsics& camera) {
  SyntheticScene scene = load_scene(options.scene);
  NoiseModel noise = parse_noise(options.noise);
  noise.kinect = options.kinect;
  try {
    noise.kinect.validate();
  } catch (const InputError& e) {
    throw InputError(std::string("kinect noise parameter ") + e.what());
  }
  Trajectory trajectory = make_trajectory(options.trajectory, scene.view, options.frames,
                                          options.trajectory_params, options.seed);
  return SyntheticSequence(std::move(scene), camera, std::move(trajectory), std::move(noise),
                           options.seed);
}

}  // namespace jpcr
