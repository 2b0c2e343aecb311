#include "jpcr/frontend/keyframe_tracker.hpp"

#include <chrono>
#include <stdexcept>

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kDegToRad = M_PI / 180.0;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Fraction of the frame's valid points at the coarsest level that pair with the keyframe at
// `T_kf_c`: a cheap overlap measure for the keyframe policy.
double overlap_with(const FramePyramid& frame, const FramePyramid& keyframe,
                    const Eigen::Isometry3d& T_kf_c, const IcpParams& icp, RowPool* pool) {
  const int l = FramePyramid::kLevels - 1;
  const NormalEquations eq = linearize_point_to_plane(frame, keyframe, l, T_kf_c, icp, 1, pool);
  return eq.valid > 0 ? static_cast<double>(eq.inliers) / eq.valid : 0.0;
}

}  // namespace

KeyframeTracker::KeyframeTracker(const FrontendParams& params,
                                 const Eigen::Isometry3d& initial_pose)
    : params_(params), initial_pose_(initial_pose) {
  params_.validate();
  pool_ = std::make_unique<RowPool>(params_.threads);
}

const Keyframe& KeyframeTracker::keyframe() const {
  if (!has_keyframe())
    throw std::logic_error("KeyframeTracker: no keyframe before the first frame");
  return keyframe_;
}

bool KeyframeTracker::is_good(const IcpResult& icp) const {
  return icp.verdict == IcpVerdict::ok ||
         (icp.verdict == IcpVerdict::degenerate && params_.tracker.accept_degenerate);
}

TrackResult KeyframeTracker::track(const Frame& frame) {
  TrackResult r;
  r.index = frames_;
  r.T_wc.timestamp = frame.timestamp;
  const Clock::time_point start = Clock::now();
  auto pyramid =
      std::make_shared<const FramePyramid>(preprocess(frame, params_.preprocess, pool_.get()));
  r.preprocess_ms = ms_since(start);

  const TrackerParams& tp = params_.tracker;
  if (frames_ == 0) {
    r.T_wc.pose = initial_pose_;
    r.is_keyframe = true;
  } else {
    const bool to_keyframe = tp.mode == TrackingMode::frame_to_keyframe;
    const FramePyramid& reference = to_keyframe ? *keyframe_.pyramid : *previous_;
    const Eigen::Isometry3d T_w_ref = to_keyframe ? keyframe_.T_wc.pose : previous_pose_;
    r.reference = to_keyframe ? keyframe_.index : frames_ - 1;
    const Eigen::Isometry3d predicted =
        previous_pose_ * (tp.motion_prior == MotionPrior::constant_velocity
                              ? last_good_motion_
                              : Eigen::Isometry3d::Identity());
    const Clock::time_point icp_start = Clock::now();
    r.icp = align_point_to_plane(*pyramid, reference, T_w_ref.inverse() * predicted, params_.icp,
                                 pool_.get());
    r.icp_ms = ms_since(icp_start);
    if (is_good(r.icp)) {
      r.T_wc.pose = T_w_ref * r.icp.pose;
      last_good_motion_ = previous_pose_.inverse() * r.T_wc.pose;
    } else {
      r.T_wc.pose = previous_pose_ * last_good_motion_;  // say so rather than drift silently
      r.kept_last_motion = true;
    }
    // Keyframe policy: far enough from the keyframe, or too little overlap with it. A failed
    // alignment against the keyframe starts a new one, or tracking could never recover.
    const Eigen::Isometry3d T_kf_c = keyframe_.T_wc.pose.inverse() * r.T_wc.pose;
    r.overlap = overlap_with(*pyramid, *keyframe_.pyramid, T_kf_c, params_.icp, pool_.get());
    r.is_keyframe = T_kf_c.translation().norm() > tp.keyframe_translation ||
                    rotation_angle(T_kf_c.linear()) > tp.keyframe_rotation * kDegToRad ||
                    r.overlap < tp.keyframe_overlap || (to_keyframe && r.kept_last_motion);
  }
  if (r.is_keyframe) {
    keyframe_.index = r.index;
    keyframe_.frame = frame;
    keyframe_.T_wc = r.T_wc;
    keyframe_.pyramid = pyramid;
    keyframe_indices_.push_back(r.index);
  }
  previous_ = std::move(pyramid);
  previous_pose_ = r.T_wc.pose;
  ++frames_;
  return r;
}

}  // namespace jpcr
