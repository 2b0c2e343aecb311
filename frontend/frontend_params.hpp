// Tunables of the front end (ICP-ftf, method.md §5): preprocessing, point-to-plane ICP and the
// keyframe tracker. Plain structs with in-class defaults and units; YAML maps onto them in io/
// (section `frontend:` of configs/default.yaml).
#pragma once

#include <array>
#include <string>

namespace jpcr {

/// Depth preprocessing and the 3-level pyramid (frame_pyramid.hpp).
struct PreprocessParams {
  float min_depth = 0.3f;    // m, nearer depth values are dropped
  float max_depth = 4.0f;    // m, farther depth values are dropped
  bool bilateral = false;    // bilateral filter of the full-resolution depth before everything else
  int bilateral_radius = 2;  // px, half-width of the filter window
  float bilateral_sigma_space = 1.5f;   // px
  float bilateral_sigma_depth = 0.02f;  // m
  /// A 2x2 block is averaged into the next level only over depths within this distance of the
  /// block's nearest depth (depth edges are not blurred).
  float pyramid_max_depth_step = 0.05f;  // m
  /// Normals are the cross product of central differences at ±normal_offset pixels at full
  /// resolution (level l uses ±max(1, normal_offset / 2^l): the same support in the scene). A
  /// difference whose depth changes by more than normal_max_jump × z per pixel of its span
  /// (2 · offset pixels) marks a depth edge, where no normal is computed.
  int normal_offset = 4;  // px
  /// false: level 0 gets no normal map of its own and borrows level 1's (the same support in the
  /// scene at a quarter of the cost); ICP at level 0 then pairs full-resolution vertices with
  /// them. true: level 0 has its own normals (for consumers that need them).
  bool full_resolution_normals = false;
  float normal_max_jump = 0.08f;  // fraction of z per pixel the difference spans

  /// Throws InputError "field: problem" for the first invalid field.
  void validate() const;
};

enum class RobustLoss { none, huber, tukey };

/// Dense projective point-to-plane ICP (point_to_plane_icp.hpp).
struct IcpParams {
  /// Gauss-Newton iterations per pyramid level, finest (640x480) first. Coarse to fine: level 2
  /// is solved first. 0 skips a level.
  std::array<int, 3> iterations{2, 2, 5};
  int level0_stride = 2;           // px, use every n-th pixel in u and v at the finest level
  float max_distance = 0.1f;       // m, pairs farther apart than this are rejected
  float max_normal_angle = 30.0f;  // deg, pairs whose normals disagree more are rejected
  RobustLoss robust_loss = RobustLoss::huber;
  float robust_scale = 0.01f;  // m, Huber's δ or Tukey's c on the point-to-plane residual
  /// Pairs are also weighted by z^−k, z the mean of the pair's two depths in m (the target's
  /// alone biased the alignment along the view): the inverse variance of an axial noise
  /// σ(z) ∝ z^(k/2). Structured-light sensors (Kinect: σ ≈ 0.0019 z² m) have k = 4; 0
  /// weighs all depths alike.
  int depth_weight_exponent = 4;
  float min_step_translation = 1e-5f;  // m, stop a level when the update is smaller ...
  float min_step_rotation = 1e-4f;     // deg, ... in both translation and rotation
  /// Relative Levenberg damping added to the diagonal of JᵀWJ (tr/6 times it). The directions
  /// the geometry does not observe at all (a plane's in-plane motions) are left out of each step.
  double damping = 1e-6;
  // Verdicts (IcpVerdict).
  /// Pairs needed at the coarsest level that runs, for a 640x480 frame (whose coarsest level is
  /// 160x120); smaller frames need proportionally fewer (by image area), finer levels
  /// proportionally more (by the pixels they sample). Fewer: `too_few_points`.
  int min_inliers = 1000;
  double min_inlier_ratio = 0.25;      // final pairs / valid source points, else `too_few_points`
  double degeneracy_threshold = 1e-3;  // λmin/λmax of the unit-free JᵀWJ below this: degenerate
  double max_translation = 0.3;  // m, a larger motion away from the initial guess is `diverged`
  double max_rotation = 30.0;    // deg, likewise

  void validate() const;
};

enum class TrackingMode { frame_to_frame, frame_to_keyframe };
enum class MotionPrior { identity, constant_velocity };

/// Keyframe tracker (keyframe_tracker.hpp).
struct TrackerParams {
  TrackingMode mode = TrackingMode::frame_to_frame;
  MotionPrior motion_prior = MotionPrior::identity;  // initial guess of each alignment
  /// A frame becomes a keyframe when it is this far from the current keyframe ...
  double keyframe_translation = 0.10;  // m
  double keyframe_rotation = 10.0;     // deg
  /// ... or when fewer than this fraction of its valid points pair with the keyframe, or when
  /// its alignment failed (frame to frame: diverged or too few points, not degenerate), so that
  /// the back end refines the extrapolated motion; never a frame without points to align to.
  double keyframe_overlap = 0.6;
  bool accept_degenerate = false;  // use a `degenerate` ICP result as if it were `ok`

  void validate() const;
};

struct FrontendParams {
  int threads = 0;  // threads of the tracker's RowPool, the caller included; 0: one per core
  PreprocessParams preprocess;
  IcpParams icp;
  TrackerParams tracker;

  void validate() const;
};

const char* to_string(RobustLoss loss);
const char* to_string(TrackingMode mode);
const char* to_string(MotionPrior prior);
/// Throw InputError listing the choices on an unknown name.
RobustLoss parse_robust_loss(const std::string& name);
TrackingMode parse_tracking_mode(const std::string& name);
MotionPrior parse_motion_prior(const std::string& name);

}  // namespace jpcr
