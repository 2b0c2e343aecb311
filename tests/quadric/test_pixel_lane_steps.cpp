// The lane-parallel halves of a Quad IT iteration (pixel_lane_steps.hpp) against the per-pixel
// functions the CUDA kernel runs: pixel_lane_steps against solve_damped_step on fresh random
// normal equations (plus a singular and a NaN lane), pixel_lane_updates against
// apply_quadric_update and step_converged, small, large and zero rotations, lanes left alone.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "jpcr/quadric/pixel_lane_steps.hpp"

namespace jpcr {
namespace {

unsigned tri(unsigned a, unsigned b) {
  return a >= b ? a * (a + 1) / 2 + b : b * (b + 1) / 2 + a;
}

TEST(PixelLaneSteps, EqualSolveDampedStepAndFlagSingularLanes) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  PixelLaneSums sums{};
  NormalEquations6<double> ne[kPixelLanes];
  for (int l = 0; l < kPixelLanes; ++l) {
    // Y = Σ (y, r)(y, r)ᵀ of 40 random samples with column scales like a 3 cm patch.
    const double scale[kQuadricColumns] = {1.0, 0.03, 0.03, 5e-4, 1e-3, 5e-4, 2e-3};
    double Y[kQuadricColumns][kQuadricColumns] = {};
    for (int k = 0; k < 40; ++k) {
      double y[kQuadricColumns];
      for (int a = 0; a < kQuadricColumns; ++a)
        y[a] = a == 0 ? 1.0 : scale[a] * n(rng);
      for (int a = 0; a < kQuadricColumns; ++a)
        for (int b = 0; b < kQuadricColumns; ++b)
          Y[a][b] += y[a] * y[b];
    }
    if (l == 3)  // J₃ ≡ 0 (no sample off the e_y axis): a zero pivot, damping or not
      for (int a = 0; a < kQuadricColumns; ++a)
        Y[kColJ3][a] = Y[a][kColJ3] = 0.0;
    if (l == 5) Y[kColJ1][kColJ0] = Y[kColJ0][kColJ1] = std::numeric_limits<double>::quiet_NaN();
    for (int a = 0; a < kQuadricColumns; ++a)
      for (int b = 0; b <= a; ++b)
        sums.products[tri(a, b)][l] = static_cast<float>(Y[a][b]);
    for (int i = 0; i < 6; ++i) {  // the same system from the float sums, as the CPU fit reads it
      for (int j = 0; j < 6; ++j)
        ne[l].H(i, j) = kGammaSign[i] * kGammaSign[j] *
                        double(sums.products[tri(kGammaColumn[i], kGammaColumn[j])][l]);
      ne[l].g(i) = kGammaSign[i] * double(sums.products[tri(kGammaColumn[i], kColR)][l]);
    }
  }
  double delta[6][kPixelLanes];
  bool ok[kPixelLanes];
  double damping[kPixelLanes];  // each lane its own, as after Quad IT's retries
  double range[kPixelLanes];    // and its own centre range, 5 cm to 8 m
  for (int l = 0; l < kPixelLanes; ++l) {
    damping[l] = l % 3 == 0 ? 0.01 : l % 3 == 1 ? 0.1 : 1.0;
    range[l] = 0.05 * std::pow(2.0, 0.5 * l);
  }
  pixel_lane_steps(sums, damping, range, delta, ok);
  for (int l = 0; l < kPixelLanes; ++l) {
    Eigen::Matrix<double, 6, 1> expected;
    const bool solved = solve_damped_step(ne[l], damping[l], range[l], expected);
    EXPECT_EQ(ok[l], solved) << "lane " << l;
    EXPECT_EQ(ok[l], l != 3 && l != 5) << "lane " << l;
    if (!solved) continue;
    for (int i = 0; i < 6; ++i)  // two factorisations of a system with κ ≈ 1e8 in double
      EXPECT_NEAR(delta[i][l], expected(i), 1e-7 * expected.cwiseAbs().maxCoeff())
          << "lane " << l << " Δ" << i;
  }
}

// The range units change how the singularity floor reads the system, not the step: (S H S +
// λ diag(S H S)) Δ' = −S g with Δ = S Δ' is (H + λ diag H) Δ = −g, since diag(S H S) = S² diag H.
// On a 3 cm patch's system (condition about 4e6) the steps at ranges 0.3 to 3 m, where such a
// patch is seen, agree to its rounding, about 4e6 · 2e-16 ≈ 1e-9 of the step; bound 1e-8. (At
// 20 m the same 3 cm patch is singular: its curvature columns fall below the floor, as they
// should for a patch far smaller than its range.)
TEST(SolveDampedStep, TheRangeUnitsGiveTheSameStep) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    NormalEquations6<double> ne;
    const double scale[6] = {0.03, 0.03, 1.0, 5e-4, 1e-3, 5e-4};  // a 3 cm patch's columns
    for (int k = 0; k < 40; ++k) {
      Eigen::Matrix<double, 6, 1> J;
      for (int i = 0; i < 6; ++i)
        J(i) = scale[i] * n(rng);
      ne.add(J, 1e-3 * n(rng), 1.0);
    }
    Eigen::Matrix<double, 6, 1> at_one, at_range;
    ASSERT_TRUE(solve_damped_step(ne, 0.01, 1.0, at_one));
    for (double range : {0.3, 1.5, 3.0}) {
      ASSERT_TRUE(solve_damped_step(ne, 0.01, range, at_range)) << range;
      for (int i = 0; i < 6; ++i)
        EXPECT_NEAR(at_range(i), at_one(i), 1e-8 * at_one.cwiseAbs().maxCoeff())
            << "range " << range << ", trial " << trial << ", Δ" << i;
    }
  }
}

TEST(PixelLaneSteps, UpdatesEqualApplyQuadricUpdateAndStepConverged) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  QuadricFitParams p;
  LaneQuadrics lanes;
  Quadricd expected[kPixelLanes];
  double delta[6][kPixelLanes];
  bool take[kPixelLanes], converged[kPixelLanes];
  for (int l = 0; l < kPixelLanes; ++l) {
    Quadricd& q = expected[l];
    q.R = local_frame<double>(Eigen::Vector3d(u(rng), u(rng), -2.0).normalized());
    q.t_z = 0.01 * u(rng), q.a = u(rng), q.b = u(rng), q.c = u(rng);
    for (int i = 0; i < 9; ++i)
      lanes.row[i][l] = q.R(i / 3, i % 3);
    lanes.row[LaneQuadrics::kTz][l] = q.t_z;
    lanes.row[LaneQuadrics::kA][l] = q.a;
    lanes.row[LaneQuadrics::kB][l] = q.b;
    lanes.row[LaneQuadrics::kC][l] = q.c;
    // Rotations from 0 (lane 0) and below the solver's tolerances (lane 1) through 0.01 to
    // 1.2 rad; lanes 13 and 15 (0.6, 1.2 rad) are beyond the series (lane 14 takes no step).
    const double angle = l == 0 ? 0.0 : l == 1 ? 1e-7 : l < 12 ? 0.01 * l : 0.3 * (l - 11);
    const double phase = u(rng) * M_PI;
    delta[0][l] = angle * std::cos(phase);
    delta[1][l] = angle * std::sin(phase);
    for (int i = 2; i < 6; ++i)
      delta[i][l] = l <= 1 ? 1e-9 * u(rng) : 0.1 * u(rng);
    take[l] = l % 5 != 4;
    if (take[l]) {
      Eigen::Matrix<double, 6, 1> d;
      for (int i = 0; i < 6; ++i)
        d(i) = delta[i][l];
      apply_quadric_update(q, QuadricVector<double>(d));
    }
  }
  pixel_lane_updates(lanes, delta, take, p, converged);
  for (int l = 0; l < kPixelLanes; ++l) {
    Eigen::Matrix<double, 6, 1> d;
    for (int i = 0; i < 6; ++i)
      d(i) = delta[i][l];
    EXPECT_EQ(converged[l], step_converged(d, p)) << "lane " << l;
    for (int i = 0; i < 9; ++i)
      EXPECT_NEAR(lanes.row[i][l], expected[l].R(i / 3, i % 3), 1e-15) << "lane " << l;
    EXPECT_EQ(lanes.row[LaneQuadrics::kTz][l], expected[l].t_z);
    EXPECT_EQ(lanes.row[LaneQuadrics::kA][l], expected[l].a);
    EXPECT_EQ(lanes.row[LaneQuadrics::kB][l], expected[l].b);
    EXPECT_EQ(lanes.row[LaneQuadrics::kC][l], expected[l].c);
  }
  EXPECT_TRUE(converged[1]);  // the tiny step
  EXPECT_FALSE(converged[2]);
}

}  // namespace
}  // namespace jpcr
