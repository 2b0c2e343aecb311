// J-full (method.md §7): joint refinement of the poses T_2 … T_M of a window of M keyframes and
// the dense quadrics of the reference keyframe, by Levenberg-Marquardt on the Schur-reduced
// system (joint_system.hpp). J-ftf (joint_frame_to_frame.hpp) is the window M = 2 and Q-full
// (fixed_quadric_alignment.hpp) the window with the quadrics held fixed; all three run the
// loop of refine_window.
#pragma once

#include "jpcr/backend/refiner.hpp"

namespace jpcr {

class JointWindow final : public Refiner {
 public:
  explicit JointWindow(const JointParams& params = {});
  using Refiner::refine;
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override;
  std::string name() const override { return "j-full"; }
  const JointParams& params() const override { return params_; }

 private:
  JointParams params_;
};

/// The CPU refinement of a window: JointSystem under the shared Levenberg-Marquardt loop
/// run_joint_refinement (joint_problem.hpp). estimate_quadrics = false is Q-full. The quadrics
/// at creases and steps stay out (edge_quadrics, joint_problem.hpp): `edges` where the caller
/// has them for vertices[0] (an empty vector leaves every quadric in), else (nullptr) computed
/// here from vertices[0] and params.quadric.normals. After the loop, with
/// params.keep_lower_cost_fit, each quadric whose Quad IT start fits the window better gets it
/// back (keep_lower_cost_fits, lower_cost_fit.hpp).
RefinementResult refine_window(const std::vector<VertexMap>& vertices,
                               const CameraIntrinsics& camera,
                               const std::vector<Eigen::Isometry3d>& initial_poses,
                               const QuadricMap& initial_quadrics, const JointParams& params,
                               bool estimate_quadrics, const std::string& method,
                               const std::vector<unsigned char>* edges = nullptr);

}  // namespace jpcr
