// ICP-ftf (method.md §5): dense projective point-to-plane ICP between two frame pyramids, coarse
// to fine, with robust weights and Gauss-Newton steps T ← exp(ξ^) T solved with LDLT.
//
//   FramePyramid source = preprocess(frame_j), target = preprocess(frame_i);
//   IcpResult r = align_point_to_plane(source, target, Eigen::Isometry3d::Identity());
//   if (r.verdict == IcpVerdict::ok) T_wc_j = T_wc_i * r.pose;
//
// The pose maps source-frame points into the target frame (method.md §1), so for consecutive
// frames it is the motion of the camera from the target to the source frame.
#pragma once

#include "jpcr/frontend/frame_pyramid.hpp"
#include "jpcr/frontend/normal_equations.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

/// Whether a result can be trusted:
///  - ok:             converged on enough pairs, well constrained;
///  - degenerate:     the smallest eigenvalue of the unit-free JᵀWJ is tiny against the largest
///                    (a plane, a corridor): some direction of motion is not observed;
///  - diverged:       the estimate is not finite or moved farther from the initial guess than
///                    max_translation / max_rotation;
///  - too_few_points: a level had fewer pairs than min_inliers (scaled), or too small a fraction
///                    of the source points found a partner (no overlap).
enum class IcpVerdict { ok, degenerate, diverged, too_few_points };

const char* to_string(IcpVerdict verdict);

struct IcpResult {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // T: source frame → target frame
  int iterations = 0;  // Gauss-Newton iterations over all levels
  /// The finest level stopped on a step below min_step, or its last step moved the pose by less
  /// than one standard deviation of the estimate (ξᵀ covariance⁻¹ ξ ≤ 1): more iterations would
  /// not change it beyond its noise. Advisory: the verdict does not use it.
  bool converged = false;
  /// The statistics below describe the final pairs, those of the last linearisation, made one
  /// Gauss-Newton step before the returned pose (a step within the noise when converged).
  double rms = 0.0;           // m, RMS point-to-plane residual of the final pairs
  double inlier_ratio = 0.0;  // final pairs / valid source points considered
  std::size_t inliers = 0;    // final pairs
  /// Eigenvalues of JᵀWJ at the final linearisation, ascending; raw, so they scale with the
  /// weights and with m² in the ω block (ξ = (v, ω)).
  Vector6d eigenvalues = Vector6d::Zero();
  /// λmin / λmax of JᵀWJ made unit-free: the ω columns are divided by the RMS lever arm
  /// √(Σ w |p × n|² / Σ w). 1 is perfectly conditioned, 0 unobservable. Noise in the normals
  /// adds information in unobservable directions; its expected part is taken out, at the finest
  /// pyramid level whose normals are not too noisy for that (the coarse levels' are less
  /// noisy). README, "A single plane seen with noisy normals is degenerate too".
  double degeneracy = 0.0;
  /// σ² (JᵀWJ)⁻¹ for ξ in the target frame (left perturbation), σ² = Σ w e² / (n − 6) over the n
  /// final pairs: the variance of a unit-weight residual. On bilateral-filtered depth
  /// (PreprocessParams::bilateral) the residuals' errors are shared between neighbouring pixels,
  /// and it is multiplied by filtered_noise_inflation (frame_pyramid.hpp; 5.0 for the default
  /// filter at stride 2). `jpcr_eval noise --method icp-ftf --noise-matched` measures the spread
  /// 1.0–1.3x the prediction in translation, 1.0–1.1x in rotation (it was 2.3–2.9x without).
  /// Eigenvalues below 1e-12 λmax are clamped, so unobserved directions read as huge, not Inf;
  /// without any pair it is the identity (1 m and 1 rad per axis: an unknown motion).
  Matrix6d covariance = Matrix6d::Identity();
  IcpVerdict verdict = IcpVerdict::too_few_points;
};

/// Aligns `source` to `target` starting from `initial` (source → target). `pool` spreads the
/// pixels over threads; null runs on the calling thread. Throws InputError for parameters that
/// IcpParams::validate refuses.
IcpResult align_point_to_plane(const FramePyramid& source, const FramePyramid& target,
                               const Eigen::Isometry3d& initial, const IcpParams& params = {},
                               RowPool* pool = nullptr);

/// One pass of association and reduction at one level: every stride-th source pixel is mapped
/// with T, projected into the target, paired with the target vertex and normal there, rejected
/// by distance and normal angle, weighted, and added to the normal equations. Throws
/// InputError for a stride below 1.
NormalEquations linearize_point_to_plane(const FramePyramid& source, const FramePyramid& target,
                                         int level, const Eigen::Isometry3d& T,
                                         const IcpParams& params, int stride = 1,
                                         RowPool* pool = nullptr);

/// Robust weight of a residual e (m) for params.robust_loss and robust_scale.
float robust_weight(float e, RobustLoss loss, float scale);

}  // namespace jpcr
