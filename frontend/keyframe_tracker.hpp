// The front end's tracker: ICP-ftf against the previous frame (the paper's baseline) or against
// the current keyframe, with a keyframe policy (translation, rotation, overlap, a failed
// alignment) that selects the frames the back end refines. A failed alignment never moves the
// camera silently: the tracker extrapolates the last good motion and says so
// (TrackResult::kept_last_motion).
//
//   KeyframeTracker tracker(params.frontend);
//   for (...) {
//     TrackResult r = tracker.track(frame);   // r.T_wc: camera-to-world (method.md §1)
//     if (r.is_keyframe) backend.add(tracker.keyframe());
//   }
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "jpcr/frontend/frame_pyramid.hpp"
#include "jpcr/frontend/point_to_plane_icp.hpp"

namespace jpcr {

/// A frame the back end works on: the frame, its pose and its preprocessed maps.
struct Keyframe {
  int index = -1;  // position of the frame in the tracked sequence (0-based)
  Frame frame;
  StampedPose T_wc;
  Matrix6d pose_covariance = Matrix6d::Zero();  // TrackResult::pose_covariance
  std::shared_ptr<const FramePyramid> pyramid;
};

struct TrackResult {
  int index = 0;       // position of the frame in the tracked sequence (0-based)
  int reference = -1;  // index of the frame it was aligned to (frame to frame: the last one with
                       // points, before a blank one); −1 for the gauge and any frame before it
  StampedPose T_wc;    // camera-to-world estimate
  IcpResult icp;       // the alignment (default-constructed, too_few_points, without reference)
  /// The first frame with the points to be aligned against is keyframe 0, the gauge
  /// (initial_pose). Frames before it (a sensor starting blank) have no reference: they keep
  /// the gauge's pose as an unknown motion (kept_last_motion, 1 m and 1 rad per axis).
  bool is_gauge = false;
  /// Covariance of T_wc as the chain of alignments from the gauge (zero)
  /// gives it: ξ of a left update exp(ξ^) T_wc in world axes, (v, ω) as IcpResult::covariance.
  /// Σ = Σ_ref + Ad(T_w,ref) Σ_icp Ad(T_w,ref)ᵀ (first-order, independent alignments); a frame
  /// that kept the last motion adds the last good alignment's Σ_icp at the previous frame (1 m
  /// and 1 rad per axis when no alignment has succeeded yet: the motion is unknown).
  /// position_rotation_covariance (se3.hpp) turns it into ROS's (x, y, z, rx, ry, rz) order.
  Matrix6d pose_covariance = Matrix6d::Zero();
  bool is_keyframe = false;
  bool kept_last_motion = false;  // the alignment failed; T_wc extrapolates the last good motion
  double overlap = 1.0;           // fraction of the frame's points that the keyframe also sees
  double preprocess_ms = 0.0;
  double icp_ms = 0.0;
};

class KeyframeTracker {
 public:
  /// `initial_pose` is the camera-to-world pose of the first frame with points, keyframe 0 (the
  /// gauge, method.md §1); usually frame 0. Throws InputError when FrontendParams::validate
  /// refuses `params` or `initial_pose` is no rigid motion (is_rigid).
  explicit KeyframeTracker(const FrontendParams& params = {},
                           const Eigen::Isometry3d& initial_pose = Eigen::Isometry3d::Identity());

  /// Tracks the next frame. Throws InputError, before the frame counts, when the frame's size
  /// differs from its camera's or its camera from the first frame's.
  TrackResult track(const Frame& frame);

  bool has_keyframe() const { return keyframe_.pyramid != nullptr; }
  /// The current keyframe; throws std::logic_error before the first frame with points.
  const Keyframe& keyframe() const;
  const std::vector<int>& keyframe_indices() const { return keyframe_indices_; }
  const FrontendParams& params() const { return params_; }
  int threads() const { return pool_->slots(); }

 private:
  bool is_good(const IcpResult& icp) const;

  FrontendParams params_;
  std::unique_ptr<RowPool> pool_;
  Eigen::Isometry3d initial_pose_;
  CameraIntrinsics camera_;  // the first frame's: every frame's
  int frames_ = 0;
  Keyframe keyframe_;
  std::vector<int> keyframe_indices_;
  // Frame to frame, the last frame that can be aligned against (can_be_reference), with its
  // pose and pose_covariance: a blank frame (a sensor blackout) does not replace it, so the
  // frame after it aligns with the one before it.
  std::shared_ptr<const FramePyramid> previous_;
  int reference_index_ = 0;
  Eigen::Isometry3d reference_pose_ = Eigen::Isometry3d::Identity();
  Matrix6d reference_covariance_ = Matrix6d::Zero();
  Eigen::Isometry3d previous_pose_ = Eigen::Isometry3d::Identity();     // the last frame's
  Eigen::Isometry3d last_good_motion_ = Eigen::Isometry3d::Identity();  // T_prev,cur
  Matrix6d previous_covariance_ = Matrix6d::Zero();  // the last frame's pose_covariance
  // Of the last good alignment's step, in the axes of its start frame; none before the first.
  std::optional<Matrix6d> last_good_step_covariance_;
};

}  // namespace jpcr
