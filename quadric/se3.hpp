// SE(3) and SO(3) helpers (method.md §1). A twist is ξ = (v, ω) ∈ R⁶, translation part first, and
// pose updates are left-multiplicative: T ← exp(ξ^) T.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace jpcr {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// [w]×, the cross-product matrix: skew(w) x = w × x.
Eigen::Matrix3d skew(const Eigen::Vector3d& w);

/// Rodrigues' formula; exact for any angle, Taylor-expanded near zero.
Eigen::Matrix3d so3_exp(const Eigen::Vector3d& w);

/// Inverse of so3_exp for a rotation matrix; the angle is in [0, π].
Eigen::Vector3d so3_log(const Eigen::Matrix3d& R);

/// exp(ξ^) for ξ = (v, ω): R = exp(ω), t = V(ω) v.
Eigen::Isometry3d se3_exp(const Vector6d& xi);

/// Inverse of se3_exp.
Vector6d se3_log(const Eigen::Isometry3d& T);

/// Adjoint of T for the (v, ω) ordering: T exp(ξ^) T⁻¹ = exp((Ad_T ξ)^).
Matrix6d se3_adjoint(const Eigen::Isometry3d& T);

/// The covariance of a pose's (position, rotation vector) error in the reference axes, the order
/// of ROS's PoseWithCovariance (x, y, z, rx, ry, rz), from the covariance of ξ = (v, ω) of a left
/// update exp(ξ^) T, T's translation being t: to first order δt = v + ω × t and δθ = ω.
Matrix6d position_rotation_covariance(const Matrix6d& left_covariance, const Eigen::Vector3d& t);

/// Rotation angle of R in radians, in [0, π], accurate for small angles.
double rotation_angle(const Eigen::Matrix3d& R);

/// Projects a nearly orthonormal matrix back onto SO(3) (drift after many updates).
Eigen::Matrix3d orthonormalize(const Eigen::Matrix3d& R);

/// T with its rotation orthonormalized. For chains of composed poses: Isometry3d's inverse
/// transposes the rotation, so a rotation off orthonormal by e gives a relative motion off by
/// about 2e, and composing such motions again and again multiplies the error.
Eigen::Isometry3d orthonormalized(const Eigen::Isometry3d& T);

/// Whether T is a rigid motion: finite, |RᵀR − I| ≤ tolerance in every entry, det R > 0, and
/// the bottom row (0, 0, 0, 1). The refiners refuse other initial poses (a scale or shear in T
/// would otherwise pass through the residuals as a false motion).
bool is_rigid(const Eigen::Isometry3d& T, double tolerance = 1e-6);

}  // namespace jpcr
