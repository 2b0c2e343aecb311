// The per-pixel joint kernel (backend/joint_pixel_kernel.hpp): analytic pose and quadric
// Jacobians of the frame-j residual against central differences, the Schur-complement step
// of JointSystem against a dense solve of the full normal equations (and the reduced S⁻¹, which
// the pose covariance rests on, against the pose block of H⁻¹), Q-full's step against the dense
// solve of its pose block, and JointSystem's reused buffers against fresh ones.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "joint_test_windows.hpp"
#include "jpcr/backend/joint_params.hpp"
#include "jpcr/backend/joint_system.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {
namespace {

using test::JointTestWindow;
using test::motion;
using test::perturbed;
using test::render_window;

// Calls body(q, Q) for every valid frame-2 sample Q of every quadric q on a 41 x 37 px grid of
// frame 1's valid pixels (q first changed by `adjust`) that projects into frame 2 at pose T.
template <typename Adjust, typename Body>
void for_each_frame_two_sample(const JointTestWindow& w, const QuadricMap& map,
                               const NeighbourhoodPattern& pattern, const JointTermParams& params,
                               const Eigen::Isometry3d& T, Adjust&& adjust, Body&& body) {
  const PinholeProjection cam{w.camera.fx, w.camera.fy, w.camera.cx, w.camera.cy};
  const VertexView view2{w.vertices[1].data(), w.vertices[1].width(), w.vertices[1].height()};
  for (int v = 20; v < w.camera.height; v += 37) {
    for (int u = 20; u < w.camera.width; u += 41) {
      if (!map.valid(u, v)) continue;
      Quadricd q = map.quadrics(u, v).template cast<double>();
      adjust(q);
      int su = 0, sv = 0;
      if (!associate(q.center, motion(T), view2, cam, params, su, sv)) continue;
      for (const PixelOffset& o : pattern.offsets) {
        if (!view2.in_bounds(su + o.du, sv + o.dv)) continue;
        const Eigen::Vector3d Q = view2(su + o.du, sv + o.dv).cast<double>();
        if (std::isfinite(Q.z())) body(q, Q);
      }
    }
  }
}

// The residual of a fixed frame-2 sample Q as a function of the pose and the quadric:
// r(exp(ξ^) T Q; γ ⊕ Δγ). Central differences with h = 1e-6 have truncation error ~h² |r'''|
// and rounding error ~1e-16 / h; both stay below 1e-8 of the derivatives here.
TEST(JointPixelKernel, FrameTwoJacobiansMatchCentralDifferences) {
  const JointTestWindow w = render_window(2, 320);
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const JointTermParams params = JointParams{}.terms(true);
  const Eigen::Isometry3d T = perturbed(w.truth[1], 0.01, 1.0);
  const double h = 1e-6;
  int checked = 0;
  const auto curved = [](Quadricd& q) {  // curved, so every term is exercised
    q.a += 0.7, q.b -= 0.3, q.c += 0.4, q.t_z += 1e-3;
  };
  for_each_frame_two_sample(
      w, map, pattern, params, T, curved, [&](const Quadricd& q, const Eigen::Vector3d& Q) {
        const Eigen::Vector3d X = T * Q;
        const QuadricLinearization<double> l = linearize_quadric(q, X);
        const Vector6d J_xi = quadric_pose_jacobian(q, l, X);
        for (int i = 0; i < 6; ++i) {
          const Vector6d e = Vector6d::Unit(i) * h;
          const double d_xi = (quadric_residual(q, Eigen::Vector3d(se3_exp(e) * T * Q)) -
                               quadric_residual(q, Eigen::Vector3d(se3_exp(-e) * T * Q))) /
                              (2 * h);
          Quadricd qp = q, qm = q;
          apply_quadric_update(qp, QuadricVector<double>(e));
          apply_quadric_update(qm, QuadricVector<double>(-e));
          const double d_gamma = (quadric_residual(qp, X) - quadric_residual(qm, X)) / (2 * h);
          EXPECT_NEAR(J_xi(i), d_xi, 1e-8 * (1 + std::abs(d_xi))) << "xi " << i;
          EXPECT_NEAR(l.J(i), d_gamma, 1e-8 * (1 + std::abs(d_gamma))) << "gamma " << i;
        }
        ++checked;
      });
  EXPECT_GT(checked, 2000);
}

// The lever arms at the foot points (ray_foot_jacobians): on a planar quadric (a = b = c = 0)
// the frame-2 Jacobians are −(g_w·u) times the derivatives of the distance t* along the unit
// ray u from the sample to the surface, with the ray moving with the pose (it starts at camera
// 2's centre) — the distance that a range error along the ray does not change. Checked for the
// pose, the tilt and the offset t_z (the curvature entries stay at the sample); noisy frames so
// that r ≠ 0 and the foot points differ from the samples.
TEST(JointPixelKernel, RayFootJacobiansAreTheDerivativesOfTheDistanceAlongTheRay) {
  const JointTestWindow w = render_window(2, 320, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  JointParams joint;
  joint.ray_min_cosine = 0.2f;
  const JointTermParams params = joint.terms(true);
  const Eigen::Isometry3d T = perturbed(w.truth[1], 0.01, 1.0);
  const double h = 1e-6;
  int checked = 0, moved = 0;
  const auto planar = [](Quadricd& q) {
    q.R = orthonormalize(q.R);
    q.a = q.b = q.c = 0.0;
    q.t_z += 2e-3;
  };
  for_each_frame_two_sample(
      w, map, pattern, params, T, planar, [&](const Quadricd& q, const Eigen::Vector3d& Q) {
        const Eigen::Vector3d X = T * Q;
        const QuadricLinearization<double> l = linearize_quadric(q, X);
        const Eigen::Vector3d origin = q.R * (q.center - T.translation());
        Vector6d J_gamma, J_xi;
        ray_foot_jacobians(q, l, origin, params.ray_min_cos2<double>(), J_gamma, J_xi);
        // t*(pose, quadric): r is affine along the ray on a plane, so t* = −r(X) / (g_w·u).
        const auto distance = [&Q](const Eigen::Isometry3d& pose, const Quadricd& quadric) {
          const Eigen::Vector3d Xp = pose * Q;
          const Eigen::Vector3d ray = (Xp - pose.translation()).normalized();
          const QuadricLinearization<double> lp = linearize_quadric(quadric, Xp);
          return -lp.r / (quadric.R.transpose() * lp.g).dot(ray);
        };
        const double c = (q.R.transpose() * l.g).dot((X - T.translation()).normalized());
        if (std::abs(c) < 0.3 * l.g.norm()) return;  // near grazing the foot point is not used
        moved += std::abs(l.r) > 1e-3 ? 1 : 0;
        for (int i = 0; i < 6; ++i) {
          const Vector6d e = Vector6d::Unit(i) * h;
          const double d_xi =
              (distance(se3_exp(e) * T, q) - distance(se3_exp(-e) * T, q)) / (2 * h);
          EXPECT_NEAR(J_xi(i), -c * d_xi, 1e-7 * (1 + std::abs(c * d_xi))) << "xi " << i;
          if (i > 2) continue;  // tilt and offset
          Quadricd qp = q, qm = q;
          apply_quadric_update(qp, QuadricVector<double>(e));
          apply_quadric_update(qm, QuadricVector<double>(-e));
          const double d_gamma = (distance(T, qp) - distance(T, qm)) / (2 * h);
          EXPECT_NEAR(J_gamma(i), -c * d_gamma, 1e-7 * (1 + std::abs(c * d_gamma)))
              << "gamma " << i;
        }
        ++checked;
      });
  EXPECT_GT(checked, 2000);
  EXPECT_GT(moved, checked / 4);  // most samples are off the surface by more than 1 mm
}

// The same through the kernel's sums: with the association and the weights fixed,
// g_xi = ½ ∂/∂ξ Σ w r², g_gamma = ½ ∂/∂γ Σ w r² and B = Σ w J_ξ J_γᵀ of the numeric Jacobians.
TEST(JointPixelKernel, FrameTermSumsMatchNumericJacobians) {
  const JointTestWindow w = render_window(2, 320);
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const JointTermParams params = JointParams{}.terms(true);
  const PinholeProjection cam{w.camera.fx, w.camera.fy, w.camera.cx, w.camera.cy};
  const VertexView view2{w.vertices[1].data(), w.vertices[1].width(), w.vertices[1].height()};
  const Eigen::Isometry3d T = perturbed(w.truth[1], 0.005, 0.5);
  const double h = 1e-6;
  int checked = 0;
  for (int v = 30; v < w.camera.height; v += 53) {
    for (int u = 30; u < w.camera.width; u += 59) {
      if (!map.valid(u, v)) continue;
      const Quadricd q = map.quadrics(u, v).cast<double>();
      int su = 0, sv = 0;
      if (!associate(q.center, motion(T), view2, cam, params, su, sv)) continue;
      const SampleGate<double> limits = SampleGate<double>::at(params.fit, q.center);
      FrameTerms<double> f;
      // The lever arms at the samples: the exact derivatives of Σ w r² (the foot points are
      // checked in RayFootJacobiansAreTheDerivativesOfTheDistanceAlongTheRay).
      accumulate_frame_terms(q, view2, motion(T), true, kNoRayFoot, pattern.offsets.data(),
                             pattern.size(), su, sv, limits, f);
      if (f.count < params.min_frame_terms) continue;
      // Numeric Jacobian rows of the gated samples, weights frozen at the linearisation point.
      Matrix6d B = Matrix6d::Zero();
      Vector6d g_xi = Vector6d::Zero(), g_gamma = Vector6d::Zero();
      for (const PixelOffset& o : pattern.offsets) {
        if (!view2.in_bounds(su + o.du, sv + o.dv)) continue;
        const Eigen::Vector3d Q = view2(su + o.du, sv + o.dv).cast<double>();
        if (!std::isfinite(Q.z())) continue;
        const Eigen::Vector3d X = T * Q;
        const double r = quadric_residual(q, X);
        if (std::abs(r) > limits.gate) continue;
        const double wgt = fair_weight(r, (X - q.center).squaredNorm(), limits.n0);
        Vector6d Jx, Jg;
        for (int i = 0; i < 6; ++i) {
          const Vector6d e = Vector6d::Unit(i) * h;
          Jx(i) = (quadric_residual(q, Eigen::Vector3d(se3_exp(e) * T * Q)) -
                   quadric_residual(q, Eigen::Vector3d(se3_exp(-e) * T * Q))) /
                  (2 * h);
          Quadricd qp = q, qm = q;
          apply_quadric_update(qp, QuadricVector<double>(e));
          apply_quadric_update(qm, QuadricVector<double>(-e));
          Jg(i) = (quadric_residual(qp, X) - quadric_residual(qm, X)) / (2 * h);
        }
        B += wgt * Jx * Jg.transpose();
        g_xi += wgt * r * Jx;
        g_gamma += wgt * r * Jg;
      }
      EXPECT_LT((f.B - B).norm(), 1e-7 * B.norm());
      EXPECT_LT((f.g_xi - g_xi).norm(), 1e-7 * g_xi.norm() + 1e-15);
      EXPECT_LT((f.g_gamma - g_gamma).norm(), 1e-7 * g_gamma.norm() + 1e-15);
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

// The full normal equations of a small window, assembled explicitly: unknowns (ξ_2 … ξ_M, γ_1 …
// γ_P), H = Σ w JᵀJ with the LM damping H_ii (1 + λ), solved densely.
struct DenseStep {
  Eigen::VectorXd poses, quadrics;
  Eigen::MatrixXd H;  // damped; poses first, then the active quadrics
  Eigen::VectorXd g;
};

DenseStep dense_step(const JointTestWindow& w, const JointState& state, const JointTermParams& p,
                     const NeighbourhoodPattern& pattern, double lambda) {
  const int M = static_cast<int>(state.poses.size()), np = 6 * (M - 1);
  std::vector<VertexView> views;
  std::vector<RigidMotion<double>> motions;
  for (int j = 0; j < M; ++j) {
    views.push_back({w.vertices[j].data(), w.vertices[j].width(), w.vertices[j].height()});
    motions.push_back(motion(state.poses[j]));
  }
  const JointWindowView<double> window{views.data(),
                                       motions.data(),
                                       M,
                                       {w.camera.fx, w.camera.fy, w.camera.cx, w.camera.cy},
                                       pattern.offsets.data(),
                                       pattern.size()};
  // The quadrics that take part (the same rule as the driver: linearize_joint_pixel says so).
  std::vector<std::pair<std::size_t, JointPixelSystem<double, kMaxWindowFrames>>> active;
  for (std::size_t i = 0; i < state.valid.size(); ++i) {
    if (!state.valid[i]) continue;
    JointPixelSystem<double, kMaxWindowFrames> sys;
    const int u = static_cast<int>(i % w.camera.width), v = static_cast<int>(i / w.camera.width);
    linearize_joint_pixel(state.quadrics[i], window, u, v, p, lambda, sys);
    if (sys.active) active.emplace_back(i, sys);
  }
  const int N = np + 6 * static_cast<int>(active.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(N, N);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(N);
  for (std::size_t k = 0; k < active.size(); ++k) {
    const std::size_t i = active[k].first;
    const Quadricd& q = state.quadrics[i];
    const int u = static_cast<int>(i % w.camera.width), v = static_cast<int>(i / w.camera.width);
    const int col = np + 6 * static_cast<int>(k);
    const SampleGate<double> limits = SampleGate<double>::at(p.fit, q.center);
    for (int j = 0; j < M; ++j) {
      FrameTerms<double> f;
      int su = u, sv = v;
      if (j > 0) {
        if (!active[k].second.seen[j - 1]) continue;
        EXPECT_TRUE(associate(q.center, motions[j], views[j], window.camera, p, su, sv));
      }
      accumulate_frame_terms(q, views[j], motions[j], j > 0, p.ray_min_cos2<double>(),
                             pattern.offsets.data(), pattern.size(), su, sv, limits, f);
      const Matrix6d C = f.C.selfadjointView<Eigen::Lower>();
      H.block<6, 6>(col, col) += C;
      g.segment<6>(col) += f.g_gamma;
      if (j == 0) continue;
      const int row = 6 * (j - 1);
      const Matrix6d A = f.A.selfadjointView<Eigen::Lower>();
      H.block<6, 6>(row, row) += A;
      H.block<6, 6>(row, col) += f.B;
      H.block<6, 6>(col, row) += f.B.transpose();
      g.segment<6>(row) += f.g_xi;
    }
  }
  H.diagonal() *= 1.0 + lambda;
  const Eigen::VectorXd x = H.ldlt().solve(-g);
  return {x.head(np), x.tail(N - np), H, g};
}

// A window's poses 1 cm / 1° off the truth and at most 50 of the reference's quadrics, on a grid
// 36 px apart (few enough for dense_step's dense H).
JointState sparse_state(const JointTestWindow& w, const QuadricMap& map) {
  JointState state;
  for (std::size_t j = 0; j < w.truth.size(); ++j)
    state.poses.push_back(j == 0 ? w.truth[0]
                                 : perturbed(w.truth[j], 0.01, 1.0, static_cast<int>(j)));
  state.quadrics.resize(map.status.size());
  state.valid.assign(map.status.size(), 0);
  int chosen = 0;
  for (int v = 24; v < w.camera.height; v += 36)
    for (int u = 24; u < w.camera.width; u += 36) {
      const std::size_t i = static_cast<std::size_t>(v) * w.camera.width + u;
      if (!map.valid(u, v) || chosen == 50) continue;
      state.quadrics[i] = map.quadrics(u, v).cast<double>();
      state.valid[i] = 1;
      ++chosen;
    }
  return state;
}

// A window of M frames with sparse_state's quadrics: its reduced system and step at λ = 1e-3 from
// the reference sums (sample by sample, as dense_step: the Schur algebra is then exact), and the
// dense solve of the same system. estimate_quadrics = false is Q-full.
struct SmallWindowStep {
  SmallWindowStep(int frames, bool estimate_quadrics)
      : M(frames),
        w(render_window(M, 320)),
        map(QuadricFit().estimate(w.vertices[0])),
        pattern(QuadricParams{}.pattern.for_width(w.camera.width)),
        p(JointParams{}.terms(estimate_quadrics)),
        state(sparse_state(w, map)),
        system(w.vertices, w.camera, pattern, p, JointSampling::kReference),
        lin(system.linearize(state, lambda)) {
    solved = JointSystem::solve_poses(lin, lambda, pose_steps);
    if (solved) step = system.step(state, lin, lambda, pose_steps);
    dense = dense_step(w, state, p, pattern, lambda);
  }
  const int M;
  const double lambda = 1e-3;
  const JointTestWindow w;
  const QuadricMap map;
  const NeighbourhoodPattern pattern;
  const JointTermParams p;
  const JointState state;
  const JointSystem system;
  const ReducedSystem lin;
  std::vector<Vector6d> pose_steps;
  bool solved = false;
  JointStep step;
  DenseStep dense;
};

class SchurStep : public ::testing::TestWithParam<int> {};

TEST_P(SchurStep, EqualsTheDenseSolveOfTheFullSystem) {
  const SmallWindowStep t(GetParam(), true);
  const int M = t.M;
  const JointState& state = t.state;
  ASSERT_GT(t.lin.active, 20);
  ASSERT_TRUE(t.solved);
  const std::vector<Vector6d>& pose_steps = t.pose_steps;
  const JointStep& step = t.step;
  const DenseStep& dense = t.dense;

  Eigen::VectorXd schur_poses(6 * (M - 1));
  for (int j = 0; j + 1 < M; ++j)
    schur_poses.segment<6>(6 * j) = pose_steps[j];
  Eigen::VectorXd schur_quadrics(dense.quadrics.size());
  int k = 0;
  for (std::size_t i = 0; i < state.valid.size(); ++i)
    if (state.valid[i] && !step.quadric_steps[i].isZero(0.0))
      schur_quadrics.segment<6>(6 * k++) = step.quadric_steps[i];
  ASSERT_EQ(6 * k, dense.quadrics.size());
  const double e_pose = (schur_poses - dense.poses).norm() / dense.poses.norm();
  const double e_quadric = (schur_quadrics - dense.quadrics).norm() / dense.quadrics.norm();
  std::printf("M = %d, %d quadrics: relative difference poses %.2e, quadrics %.2e\n", M, k, e_pose,
              e_quadric);
  EXPECT_LT(e_pose, 1e-9);
  EXPECT_LT(e_quadric, 1e-9);

  // The pose covariance rests on the undamped reduced S: S⁻¹ must be the pose block of H⁻¹ (the
  // marginal of the poses with every quadric free), in every direction, not only the step's.
  const ReducedSystem undamped = t.system.linearize(state, 0.0);
  const Eigen::MatrixXd H = dense_step(t.w, state, t.p, t.pattern, 0.0).H;
  const int np = 6 * (M - 1);
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(H.rows(), np);
  unit.topRows(np).setIdentity();
  const Eigen::MatrixXd marginal = H.ldlt().solve(unit).topRows(np);
  const Eigen::MatrixXd s_inverse = undamped.S.ldlt().solve(Eigen::MatrixXd::Identity(np, np));
  const double e_cov = (s_inverse - marginal).norm() / marginal.norm();
  std::printf("M = %d: S^-1 against the pose block of H^-1: relative difference %.2e\n", M, e_cov);
  EXPECT_LT(e_cov, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(TwoAndFourPoses, SchurStep, ::testing::Values(2, 4));

// Q-full: the quadrics are fixed, so the full system is the poses' block alone (each pose's A_j
// with its gradient, the poses uncoupled); the reduced step must be that dense solve, and the
// candidate must keep every quadric exactly.
TEST(FixedQuadricStep, EqualsTheDenseSolveOfThePoseBlockAndKeepsTheQuadrics) {
  const SmallWindowStep t(3, false);
  const int M = t.M;
  const JointState& state = t.state;
  const ReducedSystem& lin = t.lin;
  ASSERT_GT(lin.active, 20);
  ASSERT_TRUE(t.solved);
  const std::vector<Vector6d>& pose_steps = t.pose_steps;
  const JointStep& step = t.step;
  const DenseStep& dense = t.dense;
  const int np = 6 * (M - 1);
  const Eigen::VectorXd expected = dense.H.topLeftCorner(np, np).ldlt().solve(-dense.g.head(np));
  Eigen::VectorXd got(np);
  for (int j = 0; j + 1 < M; ++j)
    got.segment<6>(6 * j) = pose_steps[static_cast<std::size_t>(j)];
  const double e = (got - expected).norm() / expected.norm();
  std::printf("Q-full, %d quadrics: relative difference of the pose steps %.2e\n", lin.active, e);
  EXPECT_LT(e, 1e-9);
  // The poses are uncoupled: no block of H joins two of them.
  EXPECT_EQ(dense.H.block(0, 6, 6, 6).norm(), 0.0);
  ASSERT_EQ(step.candidate.quadrics.size(), state.quadrics.size());
  for (std::size_t i = 0; i < state.valid.size(); ++i) {
    if (!state.valid[i]) continue;
    const Quadricd &a = step.candidate.quadrics[i], &b = state.quadrics[i];
    EXPECT_TRUE(step.quadric_steps[i].isZero(0.0)) << i;
    EXPECT_TRUE(a.R == b.R && a.center == b.center && a.t_z == b.t_z && a.a == b.a && a.b == b.b &&
                a.c == b.c)
        << "quadric " << i << " moved";
  }
}

// The first M frames' true poses, each after the first 1 cm / 1° off (test::perturbed).
std::vector<Eigen::Isometry3d> perturbed_poses(const JointTestWindow& w, int M) {
  std::vector<Eigen::Isometry3d> poses{w.truth[0]};
  for (int j = 1; j < M; ++j)
    poses.push_back(perturbed(w.truth[j], 0.01, 1.0, j));
  return poses;
}

// linearize / step into buffers that hold an earlier, larger system (another state, J-ftf's
// blocks) give what fresh ones give: the blocks and active pixels are those of this state only,
// and the candidate is this state's. J-ftf, Q-full and J-full (M = 2, 2, 3).
JointState quadric_state(const QuadricMap& map, const std::vector<Eigen::Isometry3d>& poses,
                         int every) {
  JointState s;
  s.poses = poses;
  s.quadrics.resize(map.status.size());
  s.valid.assign(map.status.size(), 0);
  for (std::size_t i = 0; i < map.status.size(); i += static_cast<std::size_t>(every)) {
    s.quadrics[i] = map.quadrics[i].cast<double>();
    s.valid[i] = map.status[i] == QuadricStatus::kValid ? 1 : 0;
  }
  return s;
}

// The step test (J-ftf, J-full, Q-full) compares the same terms as the linearisation: each
// (quadric, frame) pair it counted, at the pixel it was associated to there, with the frame-1
// terms of the estimated quadrics. At a zero step (quadrics included) the candidate's cost is the
// linearisation's (to the rounding of the candidate pose's re-orthonormalisation): this checks
// the pairs' bookkeeping (a seen bit on the wrong frame drops or adds terms).
struct StepTestCase {
  int frames;
  bool estimate_quadrics;
  JointSampling sampling;
};

class StepTest : public ::testing::TestWithParam<StepTestCase> {};

TEST_P(StepTest, IsJudgedOnTheLinearisationsPairs) {
  const StepTestCase c = GetParam();
  const JointTestWindow w = render_window(c.frames, 160, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const JointTermParams p = JointParams{}.terms(c.estimate_quadrics);
  const JointSystem system(w.vertices, w.camera, pattern, p, c.sampling);
  std::vector<Eigen::Isometry3d> poses = w.truth;
  poses.back() = perturbed(poses.back(), 0.01, 1.0, 2);
  const JointState state = quadric_state(map, poses, 1);
  // Damped by 1e12, C_p leaves the quadrics' steps k − K Δξ = k at 1e-12 of their size: with
  // Δξ = 0 the candidate is the state.
  constexpr double kStill = 1e12;
  const ReducedSystem lin = system.linearize(state, kStill);
  ASSERT_GT(lin.active, 1000);
  for (const FixedPixel& f : lin.fixed_active)
    ASSERT_NE(f.seen, 0u) << "an active quadric no frame sees";
  const std::vector<Vector6d> zero(static_cast<std::size_t>(c.frames - 1), Vector6d::Zero());
  const JointStep still = system.step(state, lin, kStill, zero);
  std::printf("zero step: cost %.12g, at the linearisation %.12g\n", still.cost, lin.cost);
  EXPECT_NEAR(still.cost, lin.cost, 1e-8 * lin.cost);
}

INSTANTIATE_TEST_SUITE_P(PairWindowAndFixedQuadrics, StepTest,
                         ::testing::Values(StepTestCase{2, true, JointSampling::kReference},
                                           StepTestCase{3, true, JointSampling::kReference},
                                           StepTestCase{3, false, JointSampling::kReference},
                                           StepTestCase{2, true, JointSampling::kGathered},
                                           StepTestCase{3, true, JointSampling::kGathered},
                                           StepTestCase{3, false, JointSampling::kGathered}));

// A step that carries a frame 100 m away cannot lower the step test's cost: each sample's weight
// n₀² / (n₀² + r² + d²) keeps its distance term d² from the linearisation, and w r² grows with
// |r| up to the gate's w(g) g², so no sample costs less than it did. With d² at the candidate the
// weights of the carried samples vanished and the cost fell (J-full accepted a 170 m step on a
// corridor). Q-full, whose quadrics the step leaves alone.
TEST(StepTest, ASampleCarriedFarAwayCostsNoLessThanAtTheLinearisation) {
  const JointTestWindow w = render_window(3, 160, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const JointSystem system(w.vertices, w.camera, pattern, JointParams{}.terms(false),
                           JointSampling::kReference);
  std::vector<Eigen::Isometry3d> poses = w.truth;
  poses[2] = perturbed(poses[2], 0.01, 1.0, 2);
  const JointState state = quadric_state(map, poses, 1);
  const ReducedSystem lin = system.linearize(state, 0.0);
  ASSERT_GT(lin.active, 1000);
  Vector6d away = Vector6d::Zero();
  away.head<3>() = Eigen::Vector3d(60.0, -50.0, 55.0);  // about 100 m
  const JointStep far = system.step(state, lin, 0.0, {away, away});
  std::printf("100 m away: cost %.6g, at the linearisation %.6g\n", far.cost, lin.cost);
  EXPECT_GE(far.cost, lin.cost);
}

// The kernels hold at most kMaxWindowFrames frames: a 17th was left out of the sums while the
// reduced system counted its pose (singular S; a review's finding for direct callers, whom
// check_joint_inputs does not guard). Refused, and so is a window without a second frame.
TEST(JointSystem, AWindowOutsideTwoToSixteenFramesIsRefused) {
  const JointTestWindow w = render_window(2, 40);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const JointTermParams p = JointParams{}.terms(true);
  const std::vector<VertexMap> one(1, w.vertices[0]), most(kMaxWindowFrames, w.vertices[0]),
      too_many(kMaxWindowFrames + 1, w.vertices[0]);
  EXPECT_THROW(JointSystem(one, w.camera, pattern, p), std::invalid_argument);
  EXPECT_NO_THROW(JointSystem(most, w.camera, pattern, p));
  EXPECT_THROW(JointSystem(too_many, w.camera, pattern, p), std::invalid_argument);
}

// A vertex with x or y not finite (a caller's map; maps from depth mark a missing pixel with
// NaN in all three) is no sample, as in Quad IT: with NaN x at every 7th pixel of frame 2 the
// terms were NaN and frame 2 saw no quadric (the review measured `seen` 0, too_few_quadrics).
TEST(JointSystem, AVertexWithANonFiniteCoordinateIsNoSample) {
  const JointTestWindow w = render_window(2, 160);
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  std::vector<VertexMap> poisoned = w.vertices;
  for (std::size_t i = 0; i < poisoned[1].size(); i += 7)
    poisoned[1].data()[i].x() = std::numeric_limits<float>::quiet_NaN();
  const JointState state = quadric_state(map, w.truth, 1);
  for (JointSampling sampling : {JointSampling::kGathered, JointSampling::kReference}) {
    const JointTermParams p = JointParams{}.terms(true);
    const ReducedSystem clean =
        JointSystem(w.vertices, w.camera, pattern, p, sampling).linearize(state, 0.0);
    const ReducedSystem lin =
        JointSystem(poisoned, w.camera, pattern, p, sampling).linearize(state, 0.0);
    EXPECT_TRUE(std::isfinite(lin.cost));
    EXPECT_TRUE(lin.S.allFinite());
    EXPECT_GT(lin.seen[0], clean.seen[0] * 9 / 10) << "of " << clean.seen[0];
  }
  // A caller's "no return" 1e25 m is no sample either: the float sampler's sums overflowed on it
  // (3043 active quadrics against the double reference's 3067, which the GPU computes).
  std::vector<VertexMap> far = w.vertices;
  for (std::size_t i = 0; i < far[1].size(); i += 7)
    far[1].data()[i] = Eigen::Vector3f(0.1f, 0.2f, 1e25f);
  std::vector<ReducedSystem> lin;
  for (JointSampling sampling : {JointSampling::kGathered, JointSampling::kReference})
    lin.push_back(JointSystem(far, w.camera, pattern, JointParams{}.terms(true), sampling)
                      .linearize(state, 0.0));
  EXPECT_TRUE(std::isfinite(lin[0].cost));
  EXPECT_EQ(lin[0].active, lin[1].active);
  EXPECT_EQ(lin[0].seen, lin[1].seen);
  EXPECT_NEAR(lin[0].cost, lin[1].cost, 1e-4 * lin[1].cost);
}

// After a rejected step only the damping changes. redamp gives J-ftf's and J-full's system at the
// new λ from their kept blocks, and its step, as linearising again does (to the rounding of the
// threads' sums and of S taken as Σ A − Σ B K instead of Σ (A − B K)); Q-full's system does not
// depend on λ; a system whose blocks were over the budget is left as it was.
TEST(JointSystem, RedampGivesTheSystemLinearizedAtTheNewDamping) {
  const JointTestWindow w = render_window(4, 160, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  struct Case {
    int M;
    bool estimate_quadrics;
    std::size_t block_memory;
  };
  for (const Case c : {Case{2, true, kDefaultBlockMemory}, Case{2, false, kDefaultBlockMemory},
                       Case{3, true, kDefaultBlockMemory}, Case{4, true, kDefaultBlockMemory},
                       Case{2, true, 0}, Case{4, true, 0}}) {
    const int M = c.M;
    const bool estimate_quadrics = c.estimate_quadrics;
    SCOPED_TRACE("M = " + std::to_string(M) + (estimate_quadrics ? "" : ", Q-full") +
                 (c.block_memory == 0 ? ", no blocks kept" : ""));
    const std::vector<VertexMap> frames(w.vertices.begin(), w.vertices.begin() + M);
    const std::vector<Eigen::Isometry3d> poses = perturbed_poses(w, M);
    const JointState state = quadric_state(map, poses, 1);
    const JointSystem system(frames, w.camera, pattern, JointParams{}.terms(estimate_quadrics),
                             JointSampling::kGathered, c.block_memory);
    for (const double lambda : {0.0, 1e-2, 10.0}) {
      SCOPED_TRACE("lambda " + std::to_string(lambda));
      ReducedSystem redamped = system.linearize(state, 1e-4);
      const Eigen::MatrixXd S_before = redamped.S;
      const bool done = system.redamp(lambda, redamped);
      EXPECT_EQ(done, !estimate_quadrics || c.block_memory > 0);
      if (!done) {
        EXPECT_EQ(redamped.S, S_before);
        continue;
      }
      const ReducedSystem fresh = system.linearize(state, lambda);
      ASSERT_GT(fresh.active, 100);
      EXPECT_EQ(redamped.active, fresh.active);
      EXPECT_EQ(redamped.terms, fresh.terms);
      EXPECT_EQ(redamped.seen, fresh.seen);
      EXPECT_NEAR(redamped.cost, fresh.cost, 1e-12 * fresh.cost);
      EXPECT_LT((redamped.A_diagonal - fresh.A_diagonal).norm(), 1e-12 * fresh.A_diagonal.norm());
      const double dS = (redamped.S - fresh.S).norm() / fresh.S.norm();
      const double ds = (redamped.s - fresh.s).norm() / fresh.s.norm();
      std::printf("M = %d%s, lambda %g: S %.2g, s %.2g relative\n", M,
                  estimate_quadrics ? "" : " (Q-full)", lambda, dS, ds);
      EXPECT_LT(dS, 1e-12);  // ΣA − ΣBK against Σ(A − BK), other thread orders: 4e-15 measured
      EXPECT_LT(ds, 1e-12);
      if (estimate_quadrics && lambda > 0.0) {  // the damping moved S by far more than that
        EXPECT_GT((S_before - fresh.S).norm(), 1e-6 * fresh.S.norm());
      }
      std::vector<Vector6d> steps;
      ASSERT_TRUE(JointSystem::solve_poses(fresh, lambda, steps));
      const JointStep a = system.step(state, redamped, lambda, steps);
      const JointStep b = system.step(state, fresh, lambda, steps);
      EXPECT_NEAR(a.cost, b.cost, 1e-12 * b.cost);
      // The same blocks and the same factor (cholesky_factor reads the lower triangle, which
      // both keep to the bit): the same quadric steps to the bit.
      double largest = 0.0;
      for (std::size_t i = 0; i < a.quadric_steps.size(); ++i) {
        largest = std::max(largest, b.quadric_steps[i].cwiseAbs().maxCoeff());
        ASSERT_EQ(a.quadric_steps[i], b.quadric_steps[i]) << "pixel " << i;
      }
      if (estimate_quadrics) {
        EXPECT_GT(largest, 0.0);
      }
    }
  }
}

// The step from the kept blocks, Δγ_p = (C_p + λ diag C_p)⁻¹ (b_p − Σ_j B_jpᵀ Δξ_j), is the
// step that computes each quadric's system again, k − Σ_j K_j Δξ_j (method.md §7), to rounding;
// the blocks are kept exactly when all valid quadrics' fit in the budget.
TEST(JointSystem, KeptBlocksGiveTheStepOfTheRecomputedSystems) {
  const JointTestWindow w = render_window(4, 160, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const double lambda = 1e-3;
  for (const int M : {2, 4}) {
    SCOPED_TRACE("M = " + std::to_string(M));
    const std::vector<VertexMap> frames(w.vertices.begin(), w.vertices.begin() + M);
    const JointState state = quadric_state(map, perturbed_poses(w, M), 1);
    const auto valid = static_cast<std::size_t>(
        std::count(state.valid.begin(), state.valid.end(), static_cast<unsigned char>(1)));
    const std::size_t needed = valid * JointSystem::block_bytes(M);
    const JointTermParams p = JointParams{}.terms(true);
    const JointSystem kept(frames, w.camera, pattern, p, JointSampling::kGathered, needed);
    const JointSystem recomputed(frames, w.camera, pattern, p, JointSampling::kGathered,
                                 needed - 1);
    const ReducedSystem a = kept.linearize(state, lambda), b = recomputed.linearize(state, lambda);
    ASSERT_TRUE(a.keeps_blocks);
    ASSERT_FALSE(b.keeps_blocks);
    EXPECT_EQ(a.blocks.size(), static_cast<std::size_t>(a.active));
    EXPECT_TRUE(b.blocks.empty() && b.couplings.empty());
    ASSERT_GT(b.active, 100);
    EXPECT_EQ(a.active, b.active);
    EXPECT_LT((a.S - b.S).norm(), 1e-12 * b.S.norm());  // the threads' order only
    std::vector<Vector6d> steps;
    ASSERT_TRUE(JointSystem::solve_poses(b, lambda, steps));
    const JointStep x = kept.step(state, a, lambda, steps),
                    y = recomputed.step(state, b, lambda, steps);
    double largest = 0.0, difference = 0.0;
    for (std::size_t i = 0; i < state.valid.size(); ++i) {
      largest = std::max(largest, y.quadric_steps[i].cwiseAbs().maxCoeff());
      difference =
          std::max(difference, (x.quadric_steps[i] - y.quadric_steps[i]).cwiseAbs().maxCoeff());
    }
    std::printf("M = %d: %zu bytes per quadric, largest quadric step %.3g, difference %.2g\n", M,
                JointSystem::block_bytes(M), largest, difference);
    EXPECT_GT(largest, 0.0);
    EXPECT_LT(difference, 1e-12 * largest);  // measured 6e-16 (M = 2) and 2e-15 (M = 4)
    EXPECT_NEAR(x.cost, y.cost, 1e-12 * y.cost);
    // A step at another damping than the kept factors' is refused; without blocks it is computed.
    EXPECT_THROW(kept.step(state, a, 2 * lambda, steps), std::invalid_argument);
    EXPECT_NO_THROW(recomputed.step(state, b, 2 * lambda, steps));
  }
}

TEST(JointSystemBuffers, ReusedBuffersGiveWhatFreshOnesGive) {
  const JointTestWindow w = render_window(3, 160, "range:1");
  const QuadricMap map = QuadricFit().estimate(w.vertices[0]);
  const NeighbourhoodPattern pattern = QuadricParams{}.pattern.for_width(w.camera.width);
  const double lambda = 1e-3;
  for (const auto& [M, estimate_quadrics] : {std::pair{2, true}, {2, false}, {3, true}}) {
    SCOPED_TRACE("M = " + std::to_string(M) + (estimate_quadrics ? "" : ", Q-full"));
    const std::vector<VertexMap> frames(w.vertices.begin(), w.vertices.begin() + M);
    const std::vector<Eigen::Isometry3d> poses = perturbed_poses(w, M);
    // Every pixel's quadric, then every third: the second system is the smaller.
    const JointState before = quadric_state(map, poses, 1), state = quadric_state(map, poses, 3);
    const JointSystem system(frames, w.camera, pattern, JointParams{}.terms(estimate_quadrics),
                             JointSampling::kGatheredDouble);
    const std::vector<VertexMap> pair_frames(w.vertices.begin(), w.vertices.begin() + 2);
    const JointSystem pair(pair_frames, w.camera, pattern, JointParams{}.terms(true),
                           JointSampling::kGatheredDouble);  // borrows the frames
    std::vector<Vector6d> steps;
    ReducedSystem reused = pair.linearize(quadric_state(map, {poses[0], poses[1]}, 1), lambda);
    ASSERT_FALSE(reused.blocks.empty());
    ASSERT_TRUE(JointSystem::solve_poses(reused, lambda, steps));
    JointStep reused_step = system.step(before, system.linearize(before, lambda), lambda,
                                        std::vector<Vector6d>(M - 1, Vector6d::Constant(1e-3)));
    system.linearize(state, lambda, reused);
    const ReducedSystem fresh = system.linearize(state, lambda);
    ASSERT_EQ(reused.active, fresh.active);
    ASSERT_GT(fresh.active, 100);
    EXPECT_EQ(reused.terms, fresh.terms);
    EXPECT_EQ(reused.seen, fresh.seen);
    // Sums over threads in another order: equal to rounding.
    EXPECT_NEAR(reused.cost, fresh.cost, 1e-12 * fresh.cost);
    EXPECT_LT((reused.S - fresh.S).norm(), 1e-12 * fresh.S.norm());
    EXPECT_LT((reused.s - fresh.s).norm(), 1e-12 * fresh.s.norm());
    // The blocks' places, in pixel order (they come in the order the threads finished rows).
    auto by_pixel = [](const ReducedSystem& f) {
      std::vector<std::size_t> order(f.blocks.size());
      for (std::size_t k = 0; k < order.size(); ++k)
        order[k] = k;
      std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return f.blocks[a].pixel < f.blocks[b].pixel;
      });
      return order;
    };
    const std::vector<std::size_t> a = by_pixel(reused), b = by_pixel(fresh);
    ASSERT_EQ(a.size(), b.size());
    const bool kept = estimate_quadrics;
    EXPECT_EQ(reused.keeps_blocks, kept);
    EXPECT_EQ(a.size(), kept ? static_cast<std::size_t>(fresh.active) : 0u);
    ASSERT_EQ(reused.couplings.size(), a.size() * (M - 1));
    ASSERT_EQ(fresh.couplings.size(), b.size() * (M - 1));
    for (std::size_t k = 0; k < a.size(); ++k) {
      const QuadricBlocks &x = reused.blocks[a[k]], &y = fresh.blocks[b[k]];
      ASSERT_EQ(x.pixel, y.pixel);
      ASSERT_EQ(x.seen, y.seen);
      ASSERT_EQ(x.C, y.C);  // one pixel's blocks: the same arithmetic, bit for bit
      ASSERT_EQ(x.L, y.L);
      ASSERT_EQ(x.g_gamma, y.g_gamma);
      for (int j = 0; j + 1 < M; ++j)
        ASSERT_EQ(reused.couplings[a[k] * (M - 1) + j], fresh.couplings[b[k] * (M - 1) + j]);
    }
    // The sums before elimination: those of this system, none left from the pair's.
    ASSERT_EQ(reused.A_sum.size(), fresh.A_sum.size());
    EXPECT_EQ(fresh.A_sum.size(), kept ? 36 * (M - 1) * (M - 1) : 0);
    if (kept) {
      EXPECT_LT((reused.A_sum - fresh.A_sum).norm(), 1e-12 * fresh.A_sum.norm());
    }
    std::vector<FixedPixel> fa = reused.fixed_active, fb = fresh.fixed_active;
    std::sort(fa.begin(), fa.end());
    std::sort(fb.begin(), fb.end());
    EXPECT_EQ(fa, fb);
    EXPECT_EQ(fa.size(), estimate_quadrics ? 0u : static_cast<std::size_t>(fresh.active));

    ASSERT_TRUE(JointSystem::solve_poses(fresh, lambda, steps));
    system.step(state, reused, lambda, steps, reused_step);
    const JointStep fresh_step = system.step(state, fresh, lambda, steps);
    EXPECT_NEAR(reused_step.cost, fresh_step.cost, 1e-12 * fresh_step.cost);
    ASSERT_EQ(reused_step.candidate.quadrics.size(), fresh_step.candidate.quadrics.size());
    EXPECT_EQ(reused_step.candidate.valid, fresh_step.candidate.valid);
    for (int j = 0; j < M; ++j)
      EXPECT_TRUE(reused_step.candidate.poses[j].isApprox(fresh_step.candidate.poses[j], 1e-15));
    double quadric_difference = 0.0;
    for (std::size_t i = 0; i < state.valid.size(); ++i)
      if (state.valid[i])
        quadric_difference = std::max(
            quadric_difference,
            (reused_step.quadric_steps[i] - fresh_step.quadric_steps[i]).cwiseAbs().maxCoeff());
      else
        EXPECT_TRUE(reused_step.quadric_steps[i].isZero(0.0)) << "pixel " << i;
    EXPECT_EQ(quadric_difference, 0.0);
  }
}

}  // namespace
}  // namespace jpcr
