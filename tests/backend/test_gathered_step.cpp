// A whole J-ftf (M = 2) and J-full (M = 4) step with the CPU's gathered float sums against the
// sample-by-sample reference (backend/gathered_frame_terms.hpp); whole 320x240 frames, so minutes
// under AddressSanitizer (label slow; test_gathered_frame_terms covers the sums there).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "joint_test_windows.hpp"
#include "jpcr/backend/joint_params.hpp"
#include "jpcr/backend/joint_system.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

using test::JointTestWindow;
using test::perturbed;
using test::render_window;

// One Levenberg-Marquardt step of J-ftf (M = 2) and J-full (M = 4) from perturbed poses:
// the gathered sums, in double and in float lanes, against the reference.
class GatheredStep : public ::testing::TestWithParam<int> {};

TEST_P(GatheredStep, MatchesTheReferenceStep) {
  const int M = GetParam();
  const JointTestWindow w = render_window(M, 320, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const JointTermParams p = JointParams{}.terms(true);
  JointState state;
  for (int j = 0; j < M; ++j)
    state.poses.push_back(j == 0 ? w.truth[0] : perturbed(w.truth[j], 0.01, 1.0, j));
  for (std::size_t i = 0; i < map.status.size(); ++i) {
    state.quadrics.push_back(map.quadrics[i].cast<double>());
    state.valid.push_back(map.status[i] == QuadricStatus::kValid ? 1 : 0);
  }
  const double lambda = 1e-3;
  // The reference, the gathered sums in double lanes and in float lanes (the default).
  const JointSampling samplings[3] = {JointSampling::kReference, JointSampling::kGatheredDouble,
                                      JointSampling::kGathered};
  Eigen::VectorXd steps[3];
  double costs[3] = {0, 0, 0}, candidate_costs[3] = {0, 0, 0};
  int active[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const JointSystem system(w.vertices, w.camera, pattern, p, samplings[k]);
    const ReducedSystem lin = system.linearize(state, lambda);
    std::vector<Vector6d> pose_steps;
    ASSERT_TRUE(JointSystem::solve_poses(lin, lambda, pose_steps));
    steps[k].resize(6 * (M - 1));
    for (int j = 0; j + 1 < M; ++j)
      steps[k].segment<6>(6 * j) = pose_steps[j];
    costs[k] = lin.cost;
    active[k] = lin.active;
    candidate_costs[k] = system.step(state, lin, lambda, pose_steps).cost;
  }
  for (int k = 1; k < 3; ++k) {
    const double e_step = (steps[k] - steps[0]).norm() / steps[0].norm();
    std::printf(
        "M = %d, %s lanes: pose step relative difference %.2e, cost %.2e, candidate "
        "cost %.2e, active %d / %d\n",
        M, k == 1 ? "double" : "float", e_step, std::abs(costs[k] / costs[0] - 1),
        std::abs(candidate_costs[k] / candidate_costs[0] - 1), active[k], active[0]);
    if (k == 1) {
      // Double lanes: the same sums in another order and frame (centred on p̄), so the same
      // decisions at every sample and quadric; only rounding differs: measured 3.5e-10 (step)
      // and 6e-11 (cost) for M = 2 and 4, bounds 30x and 15x that, 400x below float lanes.
      EXPECT_EQ(active[1], active[0]);
      EXPECT_LT(e_step, 1e-8);
      EXPECT_NEAR(costs[1], costs[0], 1e-9 * costs[0]);
      EXPECT_NEAR(candidate_costs[1], candidate_costs[0], 1e-9 * candidate_costs[0]);
    } else {
      // Float lanes: the rounding of the terms averages out over ~60k quadrics (costs: measured
      // 2e-8), but it flips a few decisions (a sample's residual on the gate, an undamped C_p on
      // the edge of the pivot test), and those move the pose step: measured 4e-6 and 7e-6
      // (M = 4, 2). 1e-4 is 15x that; a wrong sum moves the step by far more (double lanes
      // above, and test_gathered_frame_terms checks each sum to 1e-11).
      EXPECT_NEAR(active[2], active[0], 1e-3 * active[0]);
      EXPECT_LT(e_step, 1e-4);
      EXPECT_NEAR(costs[2], costs[0], 1e-6 * costs[0]);
      EXPECT_NEAR(candidate_costs[2], candidate_costs[0], 1e-6 * candidate_costs[0]);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(PairAndWindow, GatheredStep, ::testing::Values(2, 4));

}  // namespace
}  // namespace jpcr
