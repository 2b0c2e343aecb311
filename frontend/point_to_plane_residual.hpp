// The point-to-plane residual of ICP-ftf (method.md §5) and its Jacobian, written once for the
// ICP loop, the tests and the back end's ICP-bundle.
//
// A source point X (source camera frame) is mapped into the target frame as p = T X and paired
// with the target vertex q and unit normal n. The residual is the distance of p from q's tangent
// plane,
//     e(T) = nᵀ (T X − q).
// Under the left-multiplicative update T ← exp(ξ^) T with ξ = (v, ω) (method.md §1),
//     exp(ξ^) p ≈ p + v + ω × p,
// so e ≈ e(T) + nᵀ v + nᵀ (ω × p) = e(T) + nᵀ v + (p × n)ᵀ ω, i.e.
//     ∂e/∂ξ = [ nᵀ, (p × n)ᵀ ]     with p = T X.
#pragma once

#include <Eigen/Core>

#include "jpcr/quadric/host_device.hpp"

namespace jpcr {

template <typename Scalar>
struct PointToPlaneResidual {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Vector6 = Eigen::Matrix<Scalar, 6, 1>;

  /// p = T X, already in the target frame; q and n the paired target vertex and normal.
  JPCR_HD static Scalar error(const Vector3& p, const Vector3& q, const Vector3& n) {
    return n.dot(p - q);
  }

  /// ∂e/∂ξ at p for the left perturbation exp(ξ^) T.
  JPCR_HD static Vector6 jacobian(const Vector3& p, const Vector3& n) {
    Vector6 J;
    J.template head<3>() = n;
    J.template tail<3>() = p.cross(n);
    return J;
  }
};

}  // namespace jpcr
