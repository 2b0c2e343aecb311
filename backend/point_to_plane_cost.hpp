// The Ceres cost of one ICP-bundle correspondence (method.md §9) with its analytic Jacobian.
//
// Poses T_i, T_j (frame → reference frame 1, method.md §1) are 7-vectors [qx qy qz qw tx ty tz]
// on ceres::ProductManifold<EigenQuaternionManifold, EuclideanManifold<3>> (pose_manifold()).
// A point X of frame i pairs with the vertex q and unit normal n of frame j:
//     e = nᵀ (T_j⁻¹ T_i X − q) = n_wᵀ (a − b),   a = T_i X,  b = T_j q,  n_w = R_j n,
// the distance of X from q's tangent plane (point_to_plane_residual.hpp), written in frame 1.
//
// Tangent Jacobian. The manifold moves a pose by R ← exp(ω) R, t ← t + δt, its tangent being
// (δ, δt) with ω = 2δ (Ceres' quaternion plus: [cos|δ|, sin|δ| δ/|δ|] ⊗ q). With r = R_i X,
//     ∂e/∂(δt_i, ω_i) = [ n_wᵀ, (r × n_w)ᵀ ]            = PointToPlaneResidual::jacobian(r, n_w)
//     ∂e/∂(δt_j, ω_j) = −[ n_wᵀ, ((a − t_j) × n_w)ᵀ ]   = −PointToPlaneResidual::jacobian(a − t_j,
//     n_w)
// (for j, δe = (ω × n_w)ᵀ (a − t_j) − n_wᵀ δt).
//
// Ambient Jacobian (what Ceres asks of a cost function). Ceres multiplies it by the manifold's
// PlusJacobian P = ∂(q ⊞ δ)/∂δ = [[q_w I − [q_v]×], [−q_vᵀ]] (4x3, orthonormal columns, Pᵀq = 0).
// ∂e/∂q = 2 ∂e/∂ω Pᵀ is the derivative of e(q/|q|) (zero along q) and gives ∂e/∂q · P = ∂e/∂δ.
#pragma once

#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Geometry>

#include "jpcr/backend/icp_bundle_association.hpp"
#include "jpcr/frontend/point_to_plane_residual.hpp"

namespace jpcr {

using PoseManifold =
    ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>;

/// The pose as the 7 numbers of PoseManifold, and back (the quaternion normalised).
void to_pose_block(const Eigen::Isometry3d& T, double* block);
Eigen::Isometry3d from_pose_block(const double* block);

class PointToPlaneCost final : public ceres::SizedCostFunction<1, 7, 7> {
 public:
  explicit PointToPlaneCost(const BundleCorrespondence& c) : c_(c) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> qi(parameters[0]), qj(parameters[1]);
    const Eigen::Map<const Eigen::Vector3d> ti(parameters[0] + 4), tj(parameters[1] + 4);
    const Eigen::Vector3d r = qi * c_.X;
    const Eigen::Vector3d a = r + ti;
    const Eigen::Vector3d n_w = qj * c_.n;
    const Eigen::Vector3d b = qj * c_.q + tj;
    residuals[0] = PointToPlaneResidual<double>::error(a, b, n_w);
    if (jacobians == nullptr) return true;
    if (jacobians[0] != nullptr)
      ambient(PointToPlaneResidual<double>::jacobian(r, n_w), qi, jacobians[0]);
    if (jacobians[1] != nullptr)
      ambient(-PointToPlaneResidual<double>::jacobian(a - tj, n_w), qj, jacobians[1]);
    return true;
  }

 private:
  // [∂e/∂q (4), ∂e/∂t (3)] from the tangent Jacobian (δt, ω): ∂e/∂q = 2 gᵀ Pᵀ with g = ∂e/∂ω,
  // i.e. vector part 2 (q_w g + g × q_v), scalar part −2 g·q_v.
  static void ambient(const Eigen::Matrix<double, 6, 1>& J, const Eigen::Quaterniond& q,
                      double* out) {
    const Eigen::Vector3d g = J.tail<3>();
    const Eigen::Vector3d qv = q.vec();
    const Eigen::Vector3d dv = 2.0 * (q.w() * g + g.cross(qv));
    out[0] = dv.x();
    out[1] = dv.y();
    out[2] = dv.z();
    out[3] = -2.0 * g.dot(qv);
    out[4] = J[0];
    out[5] = J[1];
    out[6] = J[2];
  }

  BundleCorrespondence c_;
};

}  // namespace jpcr
