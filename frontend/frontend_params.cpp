#include "jpcr/frontend/frontend_params.hpp"

#include <cmath>
#include <string>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

void require(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw InputError(std::string(field) + ": " + problem);
}

bool positive(double x) {
  return std::isfinite(x) && x > 0.0;
}

}  // namespace

void PreprocessParams::validate() const {
  require(std::isfinite(min_depth) && min_depth >= 0.0f, "min_depth", "must be >= 0 (m)");
  require(positive(max_depth) && max_depth > min_depth, "max_depth",
          "must be larger than min_depth (m)");
  require(bilateral_radius >= 1 && bilateral_radius <= 7, "bilateral_radius",
          "must be in 1..7 (px)");
  require(positive(bilateral_sigma_space), "bilateral_sigma_space", "must be positive (px)");
  require(positive(bilateral_sigma_depth), "bilateral_sigma_depth", "must be positive (m)");
  require(positive(pyramid_max_depth_step), "pyramid_max_depth_step", "must be positive (m)");
  require(normal_offset >= 1 && normal_offset <= 4, "normal_offset", "must be in 1..4 (px)");
  require(positive(normal_max_jump), "normal_max_jump", "must be positive (fraction of z)");
}

void IcpParams::validate() const {
  int total = 0;
  for (int n : iterations) {
    require(n >= 0 && n <= 100, "iterations", "each level needs 0..100 iterations");
    total += n;
  }
  require(total > 0, "iterations", "at least one level needs iterations");
  require(level0_stride >= 1 && level0_stride <= 8, "level0_stride", "must be in 1..8 (px)");
  require(positive(max_distance), "max_distance", "must be positive (m)");
  require(positive(max_normal_angle) && max_normal_angle <= 180.0f, "max_normal_angle",
          "must be in (0, 180] (deg)");
  require(positive(robust_scale), "robust_scale", "must be positive (m)");
  require(depth_weight_exponent >= 0 && depth_weight_exponent <= 6, "depth_weight_exponent",
          "must be in 0..6");
  require(std::isfinite(min_step_translation) && min_step_translation >= 0.0f,
          "min_step_translation", "must be >= 0 (m)");
  require(std::isfinite(min_step_rotation) && min_step_rotation >= 0.0f, "min_step_rotation",
          "must be >= 0 (deg)");
  require(std::isfinite(damping) && damping >= 0.0 && damping < 1.0, "damping",
          "must be in [0, 1)");
  require(min_inliers >= 6, "min_inliers", "must be at least 6 (pairs)");
  require(std::isfinite(min_inlier_ratio) && min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0,
          "min_inlier_ratio", "must be in [0, 1]");
  require(std::isfinite(degeneracy_threshold) && degeneracy_threshold >= 0.0 &&
              degeneracy_threshold < 1.0,
          "degeneracy_threshold", "must be in [0, 1)");
  require(positive(max_translation), "max_translation", "must be positive (m)");
  require(positive(max_rotation) && max_rotation <= 180.0, "max_rotation",
          "must be in (0, 180] (deg)");
}

void TrackerParams::validate() const {
  require(positive(keyframe_translation), "keyframe_translation", "must be positive (m)");
  require(positive(keyframe_rotation) && keyframe_rotation <= 180.0, "keyframe_rotation",
          "must be in (0, 180] (deg)");
  require(std::isfinite(keyframe_overlap) && keyframe_overlap >= 0.0 && keyframe_overlap <= 1.0,
          "keyframe_overlap", "must be in [0, 1]");
}

void FrontendParams::validate() const {
  require(threads >= 0 && threads <= 256, "threads", "must be in 0..256 (0: one per core)");
  preprocess.validate();
  icp.validate();
  // The pairs' weights z^-k are bounded by min_depth^-k: at 1 mm a patch outweighed a room 1e12
  // to 1 and turned a good alignment degenerate.
  require(icp.depth_weight_exponent == 0 || preprocess.min_depth >= 0.01f, "min_depth",
          "must be at least 0.01 m while icp.depth_weight_exponent weighs pairs by z^-k");
  tracker.validate();
}

const char* to_string(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::none:
      return "none";
    case RobustLoss::huber:
      return "huber";
    case RobustLoss::tukey:
      return "tukey";
  }
  return "?";
}

const char* to_string(TrackingMode mode) {
  return mode == TrackingMode::frame_to_frame ? "frame_to_frame" : "frame_to_keyframe";
}

const char* to_string(MotionPrior prior) {
  return prior == MotionPrior::identity ? "identity" : "constant_velocity";
}

RobustLoss parse_robust_loss(const std::string& name) {
  for (RobustLoss l : {RobustLoss::none, RobustLoss::huber, RobustLoss::tukey})
    if (name == to_string(l)) return l;
  throw InputError("unknown robust loss '" + name + "' (none, huber or tukey)");
}

TrackingMode parse_tracking_mode(const std::string& name) {
  for (TrackingMode m : {TrackingMode::frame_to_frame, TrackingMode::frame_to_keyframe})
    if (name == to_string(m)) return m;
  throw InputError("unknown tracking mode '" + name + "' (frame_to_frame or frame_to_keyframe)");
}

MotionPrior parse_motion_prior(const std::string& name) {
  for (MotionPrior p : {MotionPrior::identity, MotionPrior::constant_velocity})
    if (name == to_string(p)) return p;
  throw InputError("unknown motion prior '" + name + "' (identity or constant_velocity)");
}

}  // namespace jpcr
