#include "jpcr/backend/refiner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "jpcr/backend/fixed_quadric_alignment.hpp"
#ifdef JPCR_HAVE_CERES
#include "jpcr/backend/icp_bundle.hpp"
#endif
#include "jpcr/backend/joint_frame_to_frame.hpp"
#include "jpcr/backend/joint_window.hpp"
#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {

bool usable(RefinementVerdict verdict) {
  return verdict == RefinementVerdict::kConverged || verdict == RefinementVerdict::kMaxIterations;
}

bool RefinementReport::pose_usable(std::size_t j) const {
  if (pose_verdicts.empty()) return usable(verdict);
  return j >= 1 && j <= pose_verdicts.size() && usable(pose_verdicts[j - 1]);
}

PoseSpread pose_spread(const Matrix6d& covariance, const Eigen::Isometry3d& pose) {
  Eigen::Matrix<double, 3, 6> J;  // δt = [I, −[t]×] ξ
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -skew(pose.translation());
  const double tt = (J * covariance * J.transpose()).trace();
  const double rr = covariance.bottomRightCorner<3, 3>().trace();
  return {std::sqrt(std::max(0.0, tt)), std::sqrt(std::max(0.0, rr))};
}

double pose_system_degeneracy(const Eigen::MatrixXd& S) {
  const Eigen::Index n = S.rows();
  if (n == 0) return 0.0;
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  for (Eigen::Index j = 0; j < n / 6; ++j) {
    const double tv = S.block<3, 3>(6 * j, 6 * j).trace();
    const double tw = S.block<3, 3>(6 * j + 3, 6 * j + 3).trace();
    if (tv > 0.0 && tw > 0.0) d.segment<3>(6 * j + 3).setConstant(std::sqrt(tv / tw));
  }
  const Eigen::MatrixXd scaled = d.asDiagonal() * S * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled, Eigen::EigenvaluesOnly);
  const double top = eig.eigenvalues().maxCoeff();
  return top > 0.0 ? std::max(0.0, eig.eigenvalues().minCoeff()) / top : 0.0;
}

void report_pose_spread(RefinementResult& result) {
  RefinementReport& r = result.report;
  const std::vector<Eigen::Isometry3d>& T = result.poses;
  r.translation_sd.clear();
  r.rotation_sd.clear();
  r.step_translation_sd.clear();
  r.step_rotation_sd.clear();
  for (std::size_t j = 1; j < T.size() && j < result.covariance.size(); ++j) {
    const PoseSpread s = pose_spread(result.covariance[j], T[j]);
    r.translation_sd.push_back(s.translation_m);
    r.rotation_sd.push_back(s.rotation_rad);
  }
  const Eigen::MatrixXd& joint = result.joint_covariance;
  const Eigen::Index m = static_cast<Eigen::Index>(T.size()) - 1;  // poses after the gauge
  if (m < 1 || joint.rows() != 6 * m || joint.cols() != 6 * m) return;
  for (Eigen::Index j = 1; j <= m; ++j) {
    // Σ of η = ξ_j − ξ_{j−1}; pose k sits at rows 6 (k − 1) of the joint covariance.
    Matrix6d eta = joint.block<6, 6>(6 * (j - 1), 6 * (j - 1));
    if (j > 1) {
      const Eigen::Index a = 6 * (j - 2), b = 6 * (j - 1);
      eta += joint.block<6, 6>(a, a) - joint.block<6, 6>(a, b) - joint.block<6, 6>(b, a);
    }
    const Eigen::Isometry3d previous_inverse = T[static_cast<std::size_t>(j - 1)].inverse();
    const Matrix6d Ad = se3_adjoint(previous_inverse);
    const PoseSpread s =
        pose_spread(Ad * eta * Ad.transpose(), previous_inverse * T[static_cast<std::size_t>(j)]);
    r.step_translation_sd.push_back(s.translation_m);
    r.step_rotation_sd.push_back(s.rotation_rad);
  }
}

std::vector<VertexMap> window_vertex_maps(const std::vector<Frame>& frames,
                                          const std::string& method) {
  if (frames.empty()) throw std::invalid_argument(method + ": no frames");
  const CameraIntrinsics& camera = frames[0].camera;
  std::vector<VertexMap> vertices;
  for (const Frame& f : frames) {
    if (!same_pinhole(f.camera, camera))
      throw std::invalid_argument(method + ": the frames differ in size or intrinsics");
    vertices.push_back(compute_vertex_map(f.depth, camera));  // throws on a size mismatch
  }
  return vertices;
}

RefinementResult Refiner::refine(const std::vector<Frame>& frames,
                                 const std::vector<Eigen::Isometry3d>& initial_poses) const {
  const std::vector<VertexMap> vertices = window_vertex_maps(frames, name());
  const QuadricMap initial = QuadricFit(params().quadric).estimate(vertices[0]);
  return refine(vertices, frames[0].camera, initial_poses, initial);
}

JointFrameToFrame::JointFrameToFrame(const JointParams& params) : params_(params) {
  params_.validate();
}

RefinementResult JointFrameToFrame::refine(const std::vector<VertexMap>& vertices,
                                           const CameraIntrinsics& camera,
                                           const std::vector<Eigen::Isometry3d>& initial_poses,
                                           const QuadricMap& initial_quadrics) const {
  if (vertices.size() != 2) throw std::invalid_argument("j-ftf: needs exactly two frames");
  return refine_window(vertices, camera, initial_poses, initial_quadrics, params_, true, name());
}

std::unique_ptr<Refiner> make_refiner(const std::string& name, const JointParams& params,
                                      const IcpBundleParams& bundle) {
  if (name == "j-ftf") return std::make_unique<JointFrameToFrame>(params);
  if (name == "j-full") return std::make_unique<JointWindow>(params);
  if (name == "q-full") return std::make_unique<FixedQuadricAlignment>(params);
#ifdef JPCR_HAVE_CERES
  if (name == "icp-bundle") return std::make_unique<IcpBundle>(bundle);
#else
  (void)bundle;
  if (name == "icp-bundle")
    throw InputError("refiner: icp-bundle needs Ceres, which this build (JPCR_CORE_ONLY) lacks");
#endif
  throw InputError("refiner: '" + name + "' is not one of j-ftf, j-full, q-full, icp-bundle");
}

}  // namespace jpcr
