#include "jpcr/backend/joint_problem.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "jpcr/quadric/se3.hpp"
#include "jpcr/quadric/surface_normals.hpp"

namespace jpcr {

namespace {

bool too_few(const ReducedSystem& lin, const JointParams& p) {
  if (lin.active < p.min_active_quadrics) return true;
  return std::any_of(lin.seen.begin(), lin.seen.end(),
                     [&](int n) { return n < p.min_active_quadrics; });
}

bool below_tolerance(const std::vector<Vector6d>& steps, const JointParams& p) {
  for (const Vector6d& d : steps)
    if (d.head<3>().norm() >= p.translation_tolerance || d.tail<3>().norm() >= p.rotation_tolerance)
      return false;
  return true;
}

// The covariance of the poses at the final, undamped linearisation, and the degeneracy measure
// λ_min / λ_max of S made unit-free: each pose's ω columns and rows are scaled by
// √(tr S_vv / tr S_ωω), the RMS lever arm, as the front end does (IcpResult::degeneracy), so
// metres and radians weigh alike.
//
// The covariance is reuse · σ² S⁻¹. σ² S⁻¹ alone treats the terms as independent, but a sample
// enters the terms of every quadric whose neighbourhood covers it, with nearly the same residual
// (neighbouring quadrics nearly coincide), so S counts its information about `reuse` times: the
// terms per distinct sample. Each active quadric sits on one reference pixel and is seen at one
// pixel of each other frame, so the distinct samples number about active + Σ_j seen_j (Q-full:
// Σ_j seen_j). Measured (J-ftf from the true pose, 1 % range noise, room_spheres walk pair,
// 16 noise draws at 160x120, 10 at 320x240): the spread of the errors was 7–14 times σ² S⁻¹'s
// standard deviations per axis, reuse ≈ 90, and 0.8–1.5 times the inflated ones
// (tests/backend/test_joint_refinement.cpp, CovarianceMatchesTheSpreadOverNoiseDraws).
void finish_report(const ReducedSystem& lin, bool estimate_quadrics, RefinementResult& out) {
  const int n = static_cast<int>(lin.s.size());
  RefinementReport& r = out.report;
  r.active_quadrics = lin.active;
  r.seen = lin.seen;
  r.terms = lin.terms;
  out.covariance.assign(static_cast<std::size_t>(n / 6 + 1), Matrix6d::Zero());
  const long unknowns = n + (estimate_quadrics ? 6L * lin.active : 0L);
  if (lin.terms <= unknowns || lin.active == 0) return;
  r.residual_variance = lin.cost / static_cast<double>(lin.terms - unknowns);
  long distinct = estimate_quadrics ? lin.active : 0L;
  for (int seen : lin.seen)
    distinct += seen;
  r.sample_reuse =
      distinct > 0 ? std::max(1.0, static_cast<double>(lin.terms) / static_cast<double>(distinct))
                   : 1.0;
  r.degeneracy = pose_system_degeneracy(lin.S);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(lin.S);
  if (ldlt.info() != Eigen::Success || !(r.degeneracy > 0.0)) return;
  const Eigen::MatrixXd cov =
      r.sample_reuse * r.residual_variance * ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  for (int j = 0; j < n / 6; ++j)
    out.covariance[static_cast<std::size_t>(j) + 1] = cov.block<6, 6>(6 * j, 6 * j);
  out.joint_covariance = cov;
}

// The refined quadrics; one that fits fewer than min_samples of its own samples of the
// reference frame (Quad IT's rule, reference_inliers) is marked kTooFewSamples instead of
// reporting its curvature.
QuadricMap refined_map(const QuadricMap& initial, const JointState& state,
                       const VertexMap& reference, const JointParams& params,
                       bool estimate_quadrics) {
  QuadricMap map = initial;
  if (!estimate_quadrics) return map;
  const JointTermParams terms = params.terms(true);
  const std::vector<int> inliers =
      reference_inliers(reference, params.quadric.pattern_for(reference.width()), terms, state);
  for (int v = 0; v < map.height(); ++v)
    for (int u = 0; u < map.width(); ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * map.width() + u;
      if (!state.valid[i]) continue;
      if (inliers[i] < terms.fit.min_samples)
        map.set_invalid(u, v, QuadricStatus::kTooFewSamples);
      else
        map.set(u, v, state.quadrics[i].cast<float>());
    }
  return map;
}

// The relative rounding of the step test's cost (sums of float lanes; a damped step's cost
// rose by up to 2e-7 of it near a minimum before the weights were held).
constexpr double kCostRounding = 1e-6;

}  // namespace

void check_joint_inputs(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                        const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& quadrics) {
  if (vertices.size() < 2)
    throw std::invalid_argument("joint refinement: needs two frames or more");
  if (vertices.size() > static_cast<std::size_t>(kMaxWindowFrames))
    throw std::invalid_argument("joint refinement: more than " + std::to_string(kMaxWindowFrames) +
                                " frames in one window");
  for (std::size_t j = 0; j < vertices.size(); ++j)
    if (vertices[j].width() != camera.width || vertices[j].height() != camera.height)
      throw std::invalid_argument(
          "joint refinement: frame " + std::to_string(j) + " is " +
          std::to_string(vertices[j].width()) + "x" + std::to_string(vertices[j].height()) +
          ", the camera " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (poses.size() != vertices.size())
    throw std::invalid_argument("joint refinement: " + std::to_string(poses.size()) +
                                " poses for " + std::to_string(vertices.size()) + " frames");
  if (!poses[0].matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-9))
    throw std::invalid_argument("joint refinement: the first pose is the gauge and must be I");
  for (std::size_t j = 1; j < poses.size(); ++j)
    if (!is_rigid(poses[j]))
      throw std::invalid_argument("joint refinement: pose " + std::to_string(j) +
                                  " is not a rigid motion (finite, R orthonormal, det R = 1)");
  if (quadrics.width() != camera.width || quadrics.height() != camera.height)
    throw std::invalid_argument("joint refinement: the quadric map differs in size from frame 0");
}

std::vector<unsigned char> edge_quadrics(const VertexMap& reference, const JointParams& params) {
  params.validate();
  // Without the quadrants' choice every normal is its window's plane: nothing to leave out.
  if (params.edge_tilt == 0.0f || params.quadric.normals.quadrant_ratio == 0.0f) return {};
  Image<float> tilt;
  estimate_normals(reference, params.quadric.normals, &tilt);
  const float limit = params.edge_tilt * static_cast<float>(M_PI / 180.0);
  std::vector<unsigned char> edges(tilt.size());
  for (std::size_t i = 0; i < edges.size(); ++i)
    edges[i] = tilt[i] > limit ? 1 : 0;
  return edges;
}

int leave_out(const std::vector<unsigned char>& edges, JointState& state) {
  if (edges.empty()) return 0;
  if (edges.size() != state.valid.size())
    throw std::invalid_argument("leave_out: " + std::to_string(edges.size()) + " edge flags for " +
                                std::to_string(state.valid.size()) + " quadrics");
  int left_out = 0;
  for (std::size_t i = 0; i < edges.size(); ++i)
    if (edges[i] && state.valid[i]) {
      state.valid[i] = 0;
      ++left_out;
    }
  return left_out;
}

JointState initial_joint_state(const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& map) {
  JointState s;
  fill_joint_state(poses, map, s);
  return s;
}

void fill_joint_state(const std::vector<Eigen::Isometry3d>& poses, const QuadricMap& map,
                      JointState& out) {
  out.poses = poses;
  if (!out.poses.empty()) out.poses[0] = Eigen::Isometry3d::Identity();
  out.quadrics.resize(map.status.size());
  out.valid.resize(map.status.size());
  for (std::size_t i = 0; i < map.status.size(); ++i) {
    out.valid[i] = map.status[i] == QuadricStatus::kValid ? 1 : 0;
    out.quadrics[i] = map.quadrics[i].cast<double>();
  }
}

RefinementResult run_joint_refinement(JointProblem& problem, const JointParams& params,
                                      bool estimate_quadrics, const std::string& method,
                                      const QuadricMap& initial_quadrics,
                                      const VertexMap& reference) {
  RefinementResult out;
  RefinementReport& report = out.report;
  report.method = method;
  double lambda = params.initial_damping;
  ReducedSystem lin = problem.linearize(lambda);
  report.cost.push_back(lin.cost);
  report.verdict = RefinementVerdict::kMaxIterations;
  if (too_few(lin, params)) report.verdict = RefinementVerdict::kTooFewQuadrics;
  while (report.verdict == RefinementVerdict::kMaxIterations &&
         report.iterations < params.max_iterations) {
    std::vector<Vector6d> pose_steps;
    const bool solved = JointSystem::solve_poses(lin, lambda, pose_steps);
    if (solved) {
      const double cost = problem.propose(lin, lambda, pose_steps);
      const bool small = below_tolerance(pose_steps, params);
      if (std::isfinite(cost) && cost <= lin.cost) {  // accept
        problem.accept();
        ++report.iterations;
        lambda = std::max(lambda / params.damping_decrease, 1e-12);
        problem.relinearize(lambda, lin);
        report.cost.push_back(lin.cost);
        if (too_few(lin, params))
          report.verdict = RefinementVerdict::kTooFewQuadrics;
        else if (small)
          report.verdict = RefinementVerdict::kConverged;
        continue;
      }
      ++report.rejected_steps;
      // A step below the tolerances that does not lower the cost beyond its rounding: the state
      // is a minimum at the resolution the tolerances ask for. A step the cost refuses by more
      // (NaN, or far above) is no sign of a minimum: the damping grows to max_damping and the
      // verdict is diverged, not converged on the unchanged state.
      if (small && cost <= lin.cost + kCostRounding * std::abs(lin.cost)) {
        report.verdict = RefinementVerdict::kConverged;
        break;
      }
    }
    lambda *= params.damping_factor;
    if (lambda > params.max_damping || !std::isfinite(lin.cost)) {
      report.verdict = RefinementVerdict::kDiverged;
      break;
    }
    problem.redamp(lambda, lin);  // the state is unchanged: only the damping
  }
  report.damping = lambda;
  problem.redamp(0.0, lin);  // `lin` is the current state's: after every accept it is relinearised
  finish_report(lin, estimate_quadrics, out);
  const bool settled = report.verdict == RefinementVerdict::kConverged ||
                       report.verdict == RefinementVerdict::kMaxIterations;
  if (settled && report.degeneracy < params.degeneracy_threshold)
    report.verdict = RefinementVerdict::kDegenerate;
  const JointState& state = problem.state();
  out.poses = state.poses;
  report_pose_spread(out);
  out.quadrics = refined_map(initial_quadrics, state, reference, params, estimate_quadrics);
  return out;
}

}  // namespace jpcr
