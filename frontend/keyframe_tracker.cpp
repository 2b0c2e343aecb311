#include "jpcr/frontend/keyframe_tracker.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kDegToRad = M_PI / 180.0;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Fraction of the frame's valid points at the coarsest level that project onto a valid vertex
// of the keyframe at `T_kf_c`: a cheap measure of the view the two share for the keyframe
// policy. It counts before the pair rejection tests, which depth noise also trips: at 1 % range
// noise only 55 % of the points of consecutive 640x480 frames passed them, and every frame
// became a keyframe.
double overlap_with(const FramePyramid& frame, const FramePyramid& keyframe,
                    const Eigen::Isometry3d& T_kf_c, const IcpParams& icp, RowPool* pool) {
  const int l = FramePyramid::kLevels - 1;
  const NormalEquations eq = linearize_point_to_plane(frame, keyframe, l, T_kf_c, icp, 1, pool);
  return eq.valid > 0 ? static_cast<double>(eq.visible) / eq.valid : 0.0;
}

// Whether a frame has the points to be aligned against at all: at the coarsest level, as many
// points that pair with themselves (a vertex with a normal) as ICP needs inliers there
// (min_inliers, scaled by the image area as in align_point_to_plane). A frame with fewer (a
// sensor blackout, depth full of NaN) never becomes a keyframe: every later frame would fail
// against it.
bool can_be_reference(const FramePyramid& frame, const IcpParams& icp, RowPool* pool) {
  const CameraIntrinsics& full = frame.levels[0].camera;
  const double area_scale =
      std::min(1.0, static_cast<double>(full.width) * full.height / (640.0 * 480.0));
  const NormalEquations self = linearize_point_to_plane(
      frame, frame, FramePyramid::kLevels - 1, Eigen::Isometry3d::Identity(), icp, 1, pool);
  return static_cast<double>(self.inliers) >= icp.min_inliers * area_scale;
}

}  // namespace

KeyframeTracker::KeyframeTracker(const FrontendParams& params,
                                 const Eigen::Isometry3d& initial_pose)
    : params_(params), initial_pose_(initial_pose) {
  params_.validate();
  // Checked here: every later alignment starts from it, and refuses a guess that is not rigid.
  if (!is_rigid(initial_pose_))
    throw InputError("initial_pose: must be a rigid motion (finite, R orthonormal, det R = 1)");
  pool_ = std::make_unique<RowPool>(params_.threads);
}

const Keyframe& KeyframeTracker::keyframe() const {
  if (!has_keyframe())
    throw std::logic_error("KeyframeTracker: no keyframe before the first frame with points");
  return keyframe_;
}

bool KeyframeTracker::is_good(const IcpResult& icp) const {
  return icp.verdict == IcpVerdict::ok ||
         (icp.verdict == IcpVerdict::degenerate && params_.tracker.accept_degenerate);
}

TrackResult KeyframeTracker::track(const Frame& frame) {
  if (frames_ > 0 && !same_pinhole(frame.camera, camera_))
    throw InputError("frame " + std::to_string(frames_) + " (t = " +
                     std::to_string(frame.timestamp) + "): camera " + describe(frame.camera) +
                     " differs from the first frame's, " + describe(camera_));
  TrackResult r;
  r.index = frames_;
  r.T_wc.timestamp = frame.timestamp;
  const Clock::time_point start = Clock::now();
  auto pyramid =
      std::make_shared<const FramePyramid>(preprocess(frame, params_.preprocess, pool_.get()));
  r.preprocess_ms = ms_since(start);

  const TrackerParams& tp = params_.tracker;
  if (frames_ == 0) camera_ = frame.camera;
  // Whether the frame becomes the next one's reference (frame to frame).
  bool can_reference = can_be_reference(*pyramid, params_.icp, pool_.get());
  if (!has_keyframe()) {
    // The first frame with the points to be aligned against is keyframe 0, the gauge, at
    // initial_pose. A frame before it (a sensor starting blank) has nothing to be aligned to:
    // it stays at the gauge's pose, an unknown motion (1 m and 1 rad per axis), with the
    // default alignment's verdict, too_few_points.
    r.T_wc.pose = initial_pose_;
    r.is_keyframe = r.is_gauge = can_reference;
    if (!can_reference) {
      r.kept_last_motion = true;
      const Matrix6d Ad = se3_adjoint(initial_pose_);
      r.pose_covariance = Ad * Ad.transpose();
    }
  } else {
    const bool to_keyframe = tp.mode == TrackingMode::frame_to_keyframe;
    const FramePyramid& reference = to_keyframe ? *keyframe_.pyramid : *previous_;
    const Eigen::Isometry3d T_w_ref = to_keyframe ? keyframe_.T_wc.pose : reference_pose_;
    r.reference = to_keyframe ? keyframe_.index : reference_index_;
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
      // Orthonormalized (se3.hpp): the kept motion is composed again after each failed
      // alignment, and without it |RᵀR − I| grew about 5x per failure cycle, past the 1e-6 at
      // which the next alignment refuses its guess.
      last_good_motion_ = orthonormalized(previous_pose_.inverse() * r.T_wc.pose);
      const Matrix6d Ad = se3_adjoint(T_w_ref);
      r.pose_covariance = (to_keyframe ? keyframe_.pose_covariance : reference_covariance_) +
                          Ad * r.icp.covariance * Ad.transpose();
      // As the uncertainty of this frame's step, in the axes of the step's start (the previous
      // frame): against the keyframe the alignment's own axes are the keyframe's.
      const Matrix6d to_step = se3_adjoint(previous_pose_.inverse() * T_w_ref);
      last_good_step_covariance_ = to_step * r.icp.covariance * to_step.transpose();
    } else {
      r.T_wc.pose =
          orthonormalized(previous_pose_ * last_good_motion_);  // say so, not drift silently
      r.kept_last_motion = true;
      // The guessed step repeats the last good one from the previous frame, with its
      // uncertainty; before any, 1 m and 1 rad per axis: an unknown motion.
      const Matrix6d Ad = se3_adjoint(previous_pose_);
      r.pose_covariance =
          previous_covariance_ +
          Ad * last_good_step_covariance_.value_or(Matrix6d::Identity()) * Ad.transpose();
    }
    // Keyframe policy: far enough from the keyframe, or too little overlap with it, or a failed
    // alignment; but never a frame without the points to align against. Against the keyframe,
    // tracking could otherwise never recover. Frame to frame, the extrapolated motion would
    // otherwise stay in every later frame's pose until the next keyframe, unrefined, while
    // their own alignments say `ok`; as a keyframe, J-ftf refines it against the last one.
    // Not for a degenerate alignment there: a featureless view would make every frame a
    // keyframe, and J-ftf cannot observe what ICP could not.
    const bool failed =
        r.kept_last_motion && (to_keyframe || r.icp.verdict != IcpVerdict::degenerate);
    const Eigen::Isometry3d T_kf_c = keyframe_.T_wc.pose.inverse() * r.T_wc.pose;
    r.overlap = overlap_with(*pyramid, *keyframe_.pyramid, T_kf_c, params_.icp, pool_.get());
    r.is_keyframe = (T_kf_c.translation().norm() > tp.keyframe_translation ||
                     rotation_angle(T_kf_c.linear()) > tp.keyframe_rotation * kDegToRad ||
                     r.overlap < tp.keyframe_overlap || failed) &&
                    can_reference;
  }
  if (r.is_keyframe) {
    keyframe_.index = r.index;
    keyframe_.frame = frame;
    keyframe_.T_wc = r.T_wc;
    keyframe_.pose_covariance = r.pose_covariance;
    keyframe_.pyramid = pyramid;
    keyframe_indices_.push_back(r.index);
  }
  if (can_reference) {
    previous_ = std::move(pyramid);
    reference_index_ = r.index;
    reference_pose_ = r.T_wc.pose;
    reference_covariance_ = r.pose_covariance;
  }
  previous_pose_ = r.T_wc.pose;
  previous_covariance_ = r.pose_covariance;
  ++frames_;
  return r;
}

}  // namespace jpcr
