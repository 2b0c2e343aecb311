// The Levenberg-Marquardt loop of the joint refiners (run_joint_refinement, joint_problem.hpp)
// on scripted problems whose answer is known in closed form: a quadratic cost
// f(ξ) = (ξ − ξ*)ᵀ W (ξ − ξ*) + c₀ in one pose (Q-full's shape: no quadrics), so the Gauss-Newton
// system is S = W, s = W (ξ* − ξ) exactly. Checked: convergence to ξ* with a cost that never
// rises, steps that raise the cost (or give NaN) are refused and leave the state alone, the
// iteration cap, the degeneracy verdict, and the covariance reuse · σ² S⁻¹ of method.md §6.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "jpcr/backend/joint_problem.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

constexpr int kActive = 1000;  // quadrics "seen", far above min_active_quadrics
constexpr long kTerms = 1000000;
constexpr double kFloor = 2.5;  // c₀: the cost at the optimum

class QuadraticProblem final : public JointProblem {
 public:
  QuadraticProblem(const Matrix6d& W, const Vector6d& optimum, const Vector6d& start)
      : W_(W), optimum_(optimum), x_(start) {
    sync_state();
  }

  ReducedSystem linearize(double /*lambda*/) override {
    ReducedSystem r;
    r.S = W_;
    r.s = W_ * (optimum_ - x_);
    r.A_diagonal = W_.diagonal();
    r.cost = cost_at(x_);
    r.terms = kTerms;
    r.active = kActive;
    r.seen = {kActive};
    ++linearizations;
    return r;
  }

  double propose(const ReducedSystem& /*system*/, double /*lambda*/,
                 const std::vector<Vector6d>& pose_steps) override {
    candidate_ = x_ + pose_steps.at(0);
    ++proposals;
    return scripted_cost ? scripted_cost(proposals) : cost_at(candidate_);
  }

  void accept() override {
    x_ = candidate_;
    ++accepted;
    sync_state();
  }

  const JointState& state() override { return state_; }

  double cost_at(const Vector6d& x) const {
    return (x - optimum_).dot(W_ * (x - optimum_)) + kFloor;
  }
  const Vector6d& x() const { return x_; }

  /// When set, propose() returns scripted_cost(n) for its n-th call instead of the true cost.
  double (*scripted_cost)(int) = nullptr;
  int linearizations = 0, proposals = 0, accepted = 0;

 private:
  void sync_state() { state_.poses = {Eigen::Isometry3d::Identity(), se3_exp(x_)}; }

  Matrix6d W_;
  Vector6d optimum_, x_, candidate_ = Vector6d::Zero();
  JointState state_;
};

Matrix6d well_conditioned() {
  Matrix6d A = Matrix6d::Identity();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      A(i, j) += 0.1 * std::sin(1.0 + i + 2.0 * j);
  return 1e4 * (A * A.transpose() + Matrix6d::Identity());
}

Vector6d optimum() {
  return (Vector6d() << 0.01, -0.02, 0.005, 0.003, -0.001, 0.002).finished();
}

RefinementResult run(QuadraticProblem& problem, const JointParams& params) {
  const QuadricMap map(2, 2);
  const VertexMap reference(2, 2, Eigen::Vector3f::Zero());
  return run_joint_refinement(problem, params, false, "q-full", map, reference);
}

TEST(JointLoop, ConvergesToTheMinimumWithACostThatNeverRises) {
  QuadraticProblem problem(well_conditioned(), optimum(), Vector6d::Zero());
  const RefinementResult r = run(problem, JointParams{});
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kConverged);
  EXPECT_LT((problem.x() - optimum()).norm(), 1e-9);
  ASSERT_EQ(r.report.cost.size(), static_cast<std::size_t>(r.report.iterations) + 1);
  for (std::size_t k = 1; k < r.report.cost.size(); ++k)
    EXPECT_LE(r.report.cost[k], r.report.cost[k - 1]) << "iteration " << k;
  EXPECT_NEAR(r.report.cost.back(), kFloor, 1e-9);
  // Gauss-Newton on a quadratic: one damped step lands within λ of the minimum, the next on it.
  EXPECT_LE(r.report.iterations, 4);
  EXPECT_EQ(r.report.rejected_steps, 0);
  EXPECT_TRUE(r.poses[1].isApprox(se3_exp(optimum()), 1e-9));
}

// Covariance = reuse · σ² S⁻¹ at the final, undamped system: reuse = terms / distinct samples
// (Q-full: the samples seen, kActive), σ² = cost / (terms − 6).
TEST(JointLoop, CovarianceIsTheInflatedInverseOfS) {
  const Matrix6d W = well_conditioned();
  QuadraticProblem problem(W, optimum(), Vector6d::Zero());
  const RefinementResult r = run(problem, JointParams{});
  const double reuse = static_cast<double>(kTerms) / kActive;
  const double sigma2 = kFloor / static_cast<double>(kTerms - 6);
  EXPECT_NEAR(r.report.sample_reuse, reuse, 1e-12 * reuse);
  EXPECT_NEAR(r.report.residual_variance, sigma2, 1e-9 * sigma2);
  ASSERT_EQ(r.covariance.size(), 2u);
  EXPECT_TRUE(r.covariance[0].isZero(0.0));  // the gauge
  const Matrix6d expected = reuse * sigma2 * W.inverse();
  EXPECT_LT((r.covariance[1] - expected).norm(), 1e-9 * expected.norm());
}

// A step that raises the cost, or whose cost is not a number, is refused: λ grows by
// damping_factor each time until it passes max_damping, and the state never moves.
TEST(JointLoop, RefusedStepsLeaveTheStateAndEndDiverged) {
  for (double (*cost)(int) :
       {+[](int) { return 1e30; }, +[](int) { return std::numeric_limits<double>::quiet_NaN(); }}) {
    QuadraticProblem problem(well_conditioned(), optimum(), Vector6d::Zero());
    problem.scripted_cost = cost;
    JointParams params;  // tolerances 0: a tiny refused step is not taken for a minimum
    params.translation_tolerance = params.rotation_tolerance = 0.0;
    const RefinementResult r = run(problem, params);
    EXPECT_EQ(r.report.verdict, RefinementVerdict::kDiverged);
    EXPECT_EQ(problem.accepted, 0);
    EXPECT_EQ(r.report.iterations, 0);
    EXPECT_TRUE(problem.x().isZero(0.0));
    // λ from initial_damping past max_damping by damping_factor: 11 refused steps by default.
    int expected = 0;
    for (double lambda = params.initial_damping; lambda <= params.max_damping;
         lambda *= params.damping_factor)
      ++expected;
    EXPECT_EQ(r.report.rejected_steps, expected);
    EXPECT_GT(r.report.damping, params.max_damping);
    ASSERT_EQ(r.report.cost.size(), 1u);
    // With the default tolerances the refused steps soon fall below them; a step refused by a
    // NaN or far higher cost is still no minimum (it used to end `converged` on the start).
    QuadraticProblem again(well_conditioned(), optimum(), Vector6d::Zero());
    again.scripted_cost = cost;
    const RefinementResult d = run(again, JointParams{});
    EXPECT_EQ(d.report.verdict, RefinementVerdict::kDiverged);
    EXPECT_EQ(d.report.rejected_steps, expected);
  }
}

// With the tolerances at 0 no step is small enough, so the loop stops at max_iterations; each
// accepted step cost one proposal.
TEST(JointLoop, StopsAtMaxIterations) {
  QuadraticProblem problem(well_conditioned(), optimum(), Vector6d::Zero());
  JointParams params;
  params.max_iterations = 7;
  params.translation_tolerance = params.rotation_tolerance = 0.0;
  const RefinementResult r = run(problem, params);
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kMaxIterations);
  EXPECT_EQ(r.report.iterations, 7);
  EXPECT_EQ(problem.accepted, 7);
  EXPECT_EQ(r.report.cost.size(), 8u);
}

// A direction the cost barely sees (one eigenvalue 1e-9 of the others): the loop settles, but
// the verdict says the pose is not observable, and the measure is that ratio after the
// metres-radians scaling.
TEST(JointLoop, AnUnobservableDirectionIsDegenerate) {
  Matrix6d W = 1e4 * Matrix6d::Identity();
  W(5, 5) = 1e-5;
  QuadraticProblem problem(W, optimum(), Vector6d::Zero());
  const RefinementResult r = run(problem, JointParams{});
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kDegenerate);
  // ω scaled by √(tr S_vv / tr S_ωω) = √(3e4 / (2e4 + 1e-5)): eigenvalues 1.5e4 and 1.5e-5.
  EXPECT_NEAR(r.report.degeneracy, 1e-9, 1e-12);
}

// Too few quadrics seen from the start: no step is tried.
TEST(JointLoop, TooFewQuadricsTriesNoStep) {
  QuadraticProblem problem(well_conditioned(), optimum(), Vector6d::Zero());
  JointParams params;
  params.min_active_quadrics = kActive + 1;
  const RefinementResult r = run(problem, params);
  EXPECT_EQ(r.report.verdict, RefinementVerdict::kTooFewQuadrics);
  EXPECT_EQ(problem.proposals, 0);
  EXPECT_TRUE(problem.x().isZero(0.0));
}

}  // namespace
}  // namespace jpcr
