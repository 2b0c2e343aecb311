#include "jpcr/backend/joint_window.hpp"

#include "jpcr/backend/joint_problem.hpp"
#include "jpcr/backend/lower_cost_fit.hpp"

namespace jpcr {

const char* to_string(RefinementVerdict verdict) {
  switch (verdict) {
    case RefinementVerdict::kConverged:
      return "converged";
    case RefinementVerdict::kMaxIterations:
      return "max_iterations";
    case RefinementVerdict::kDiverged:
      return "diverged";
    case RefinementVerdict::kTooFewQuadrics:
      return "too_few_quadrics";
    case RefinementVerdict::kNoOverlap:
      return "no_overlap";
    case RefinementVerdict::kDegenerate:
      return "degenerate";
    case RefinementVerdict::kError:
      return "error";
  }
  return "unknown";
}

RefinementResult refine_window(const std::vector<VertexMap>& vertices,
                               const CameraIntrinsics& camera,
                               const std::vector<Eigen::Isometry3d>& initial_poses,
                               const QuadricMap& initial_quadrics, const JointParams& params,
                               bool estimate_quadrics, const std::string& method,
                               const std::vector<unsigned char>* edges) {
  check_joint_inputs(vertices, camera, initial_poses, initial_quadrics);
  const JointSystem system(vertices, camera, params.quadric.pattern_for(camera.width),
                           params.terms(estimate_quadrics), JointSampling::kGathered,
                           block_memory_bytes(params));
  JointState initial = initial_joint_state(initial_poses, initial_quadrics);
  const int left_out = leave_out(edges ? *edges : edge_quadrics(vertices[0], params), initial);
  CpuJointProblem problem(system, std::move(initial));
  RefinementResult result = run_joint_refinement(problem, params, estimate_quadrics, method,
                                                 initial_quadrics, vertices[0]);
  result.report.edge_quadrics = left_out;
  if (estimate_quadrics && params.keep_lower_cost_fit && result.report.iterations > 0)
    result.report.quad_it_fits_restored = keep_lower_cost_fits(
        vertices, camera, result.poses, params, initial_quadrics, result.quadrics);
  return result;
}

JointWindow::JointWindow(const JointParams& params) : params_(params) {
  params_.validate();
}

RefinementResult JointWindow::refine(const std::vector<VertexMap>& vertices,
                                     const CameraIntrinsics& camera,
                                     const std::vector<Eigen::Isometry3d>& initial_poses,
                                     const QuadricMap& initial_quadrics) const {
  return refine_window(vertices, camera, initial_poses, initial_quadrics, params_, true, name());
}

}  // namespace jpcr
