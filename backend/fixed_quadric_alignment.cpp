#include "jpcr/backend/fixed_quadric_alignment.hpp"

#include <algorithm>

#include "jpcr/backend/joint_problem.hpp"
#include "jpcr/backend/joint_window.hpp"

namespace jpcr {

namespace {

// The window's verdict: usable when every pose is (converged only if all converged), else the
// first pose's that is not, so that a caller reading only `verdict` uses no pose of a window
// with a failed one (pose_verdicts says which poses it may still use).
RefinementVerdict window_verdict(const std::vector<RefinementVerdict>& poses) {
  for (RefinementVerdict v : poses)
    if (!usable(v)) return v;
  for (RefinementVerdict v : poses)
    if (v == RefinementVerdict::kMaxIterations) return v;
  return RefinementVerdict::kConverged;
}

// The pose problems of method.md §8 side by side: their cost is the sum of theirs (a pose that
// ended keeps its last cost), the covariance block-diagonal (no residual couples two poses).
RefinementResult combine(const std::vector<RefinementResult>& alone, const QuadricMap& quadrics,
                         const std::string& method) {
  RefinementResult out;
  RefinementReport& r = out.report;
  r.method = method;
  out.poses.push_back(Eigen::Isometry3d::Identity());
  out.covariance.push_back(Matrix6d::Zero());
  out.quadrics = quadrics;
  std::size_t longest = 0;
  double cost = 0.0;
  long seen = 0;
  bool joint = true;
  r.degeneracy = 1.0;
  for (const RefinementResult& a : alone) {
    const RefinementReport& p = a.report;
    out.poses.push_back(a.poses[1]);
    out.covariance.push_back(a.covariance.size() > 1 ? a.covariance[1] : Matrix6d::Zero());
    joint = joint && a.joint_covariance.rows() == 6;
    r.pose_verdicts.push_back(p.verdict);
    r.iterations = std::max(r.iterations, p.iterations);
    r.rejected_steps += p.rejected_steps;
    r.active_quadrics = std::max(r.active_quadrics, p.active_quadrics);
    r.edge_quadrics = p.edge_quadrics;  // the same reference and flags in every pose problem
    r.seen.push_back(p.seen.empty() ? 0 : p.seen[0]);
    r.terms += p.terms;
    r.damping = std::max(r.damping, p.damping);
    r.degeneracy = std::min(r.degeneracy, p.degeneracy);
    longest = std::max(longest, p.cost.size());
    cost += p.cost.empty() ? 0.0 : p.cost.back();
    seen += r.seen.back();
  }
  r.verdict = window_verdict(r.pose_verdicts);
  r.cost.assign(longest, 0.0);
  for (const RefinementResult& a : alone)
    for (std::size_t i = 0; i < longest && !a.report.cost.empty(); ++i)
      r.cost[i] += a.report.cost[std::min(i, a.report.cost.size() - 1)];
  // Pooled over the poses as finish_report pools over the terms (6 unknowns per pose).
  const long unknowns = 6L * static_cast<long>(alone.size());
  if (r.terms > unknowns) r.residual_variance = cost / static_cast<double>(r.terms - unknowns);
  if (seen > 0)
    r.sample_reuse = std::max(1.0, static_cast<double>(r.terms) / static_cast<double>(seen));
  if (joint) {
    const Eigen::Index n = 6 * static_cast<Eigen::Index>(alone.size());
    out.joint_covariance = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t j = 0; j < alone.size(); ++j)
      out.joint_covariance.block<6, 6>(6 * static_cast<Eigen::Index>(j),
                                       6 * static_cast<Eigen::Index>(j)) = alone[j].covariance[1];
  }
  report_pose_spread(out);
  return out;
}

}  // namespace

FixedQuadricAlignment::FixedQuadricAlignment(const JointParams& params) : params_(params) {
  params_.validate();
}

// Each pose T_j against the reference's fixed quadrics is its own problem (method.md §8): its own
// damping, step test and verdict, so a frame that sees too few quadrics, or whose cost will not
// fall, fails alone.
RefinementResult FixedQuadricAlignment::refine(const std::vector<VertexMap>& vertices,
                                               const CameraIntrinsics& camera,
                                               const std::vector<Eigen::Isometry3d>& initial_poses,
                                               const QuadricMap& initial_quadrics) const {
  check_joint_inputs(vertices, camera, initial_poses, initial_quadrics);
  const std::vector<unsigned char> edges = edge_quadrics(vertices[0], params_);
  std::vector<RefinementResult> alone;
  for (std::size_t j = 1; j < vertices.size(); ++j)
    alone.push_back(refine_window({vertices[0], vertices[j]}, camera,
                                  {initial_poses[0], initial_poses[j]}, initial_quadrics, params_,
                                  false, name(), &edges));
  return combine(alone, initial_quadrics, name());
}

}  // namespace jpcr
