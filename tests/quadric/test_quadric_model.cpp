// Property tests of the quadric model (method.md §3, §6): analytic against central-difference
// Jacobians for the quadric parameters and the pose, the closed-form principal curvatures and
// directions against an eigen-solver, the local frame, and the small dense Cholesky solve.
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "jpcr/quadric/dense_cholesky.hpp"
#include "jpcr/quadric/quadric_model.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

Quadricd random_quadric(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Quadricd q;
  q.R = local_frame<double>(Eigen::Vector3d(0.3 * n(rng), 0.3 * n(rng), -1.0).normalized());
  q.center = Eigen::Vector3d(0.2 * n(rng), 0.2 * n(rng), 1.5 + 0.2 * n(rng));
  q.t_z = 0.002 * n(rng);
  q.a = 3.0 * n(rng);
  q.b = 3.0 * n(rng);
  q.c = 3.0 * n(rng);
  return q;
}

Eigen::Vector3d near_point(const Quadricd& q, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 0.02);  // a neighbourhood a few cm wide
  return q.center + Eigen::Vector3d(n(rng), n(rng), n(rng));
}

// Central differences with step h have error O(h²·r''') ≈ 1e-10 here; the 1e-6 relative bound of
// the issue leaves a wide margin.
TEST(QuadricModel, QuadricJacobianMatchesCentralDifferences) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const Quadricd q = random_quadric(rng);
    const Eigen::Vector3d X = near_point(q, rng);
    const QuadricLinearization<double> l = linearize_quadric(q, X);
    EXPECT_NEAR(l.r, quadric_residual(q, X), 1e-15);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      QuadricVector<double> d = QuadricVector<double>::Zero();
      d(k) = h;
      Quadricd qp = q, qm = q;
      apply_quadric_update(qp, d);
      apply_quadric_update(qm, QuadricVector<double>(-d));
      const double numeric = (quadric_residual(qp, X) - quadric_residual(qm, X)) / (2 * h);
      EXPECT_NEAR(l.J(k), numeric, 1e-6 * std::max(1e-3, std::abs(numeric))) << "parameter " << k;
    }
  }
}

TEST(QuadricModel, PoseJacobianMatchesCentralDifferences) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Quadricd q = random_quadric(rng);
    Vector6d xi0;
    for (int i = 0; i < 6; ++i)
      xi0(i) = 0.05 * n(rng);
    const Eigen::Isometry3d T = se3_exp(xi0);
    const Eigen::Vector3d Q = T.inverse() * near_point(q, rng);  // a frame-2 point
    const Eigen::Vector3d X = T * Q;
    const QuadricLinearization<double> l = linearize_quadric(q, X);
    const Vector6d J = quadric_pose_jacobian(q, l, X);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vector6d d = Vector6d::Zero();
      d(k) = h;
      const double rp = quadric_residual(q, Eigen::Vector3d(se3_exp(d) * T * Q));
      const double rm = quadric_residual(q, Eigen::Vector3d(se3_exp(-d) * T * Q));
      const double numeric = (rp - rm) / (2 * h);
      EXPECT_NEAR(J(k), numeric, 1e-6 * std::max(1e-3, std::abs(numeric))) << "twist " << k;
    }
  }
}

TEST(QuadricModel, PrincipalCurvaturesAreEigenvaluesAndDirectionIsEigenvector) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 500; ++trial) {
    const Quadricd q = random_quadric(rng);
    Eigen::Matrix2d K;
    K << q.a, q.b, q.b, q.c;
    const Eigen::Vector2d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(K).eigenvalues();
    const Eigen::Vector2d kappa = principal_curvatures(q.a, q.b, q.c);
    EXPECT_GE(kappa.x(), kappa.y());
    EXPECT_NEAR(kappa.x(), ev(1), 1e-12 * (1 + ev.cwiseAbs().maxCoeff()));
    EXPECT_NEAR(kappa.y(), ev(0), 1e-12 * (1 + ev.cwiseAbs().maxCoeff()));
    // d₁ in local (x, y) is an eigenvector of K for κ₁, and lies in the tangent plane.
    const Eigen::Vector3d d1 = principal_direction(q);
    const Eigen::Vector3d local = q.R * d1;
    EXPECT_NEAR(local.z(), 0.0, 1e-12);
    EXPECT_NEAR(d1.norm(), 1.0, 1e-12);
    const Eigen::Vector2d w = local.head<2>();
    EXPECT_LT((K * w - kappa.x() * w).norm(), 1e-9 * (1 + std::abs(kappa.x())));
    // The half-angle formulas are ½ atan2(2b, a − c) itself, sign included, for b ≠ 0.
    const double phi = 0.5 * std::atan2(2 * q.b, q.a - q.c);
    EXPECT_NEAR(local.x(), std::cos(phi), 1e-12);
    EXPECT_NEAR(local.y(), std::sin(phi), 1e-12);
  }
  // Diagonal K (b = 0): φ = 0 for a > c, π/2 for a < c; an umbilic gives e_x.
  for (const Eigen::Vector3d& abc : {Eigen::Vector3d(2, 0, 1), Eigen::Vector3d(1, 0, 2),
                                     Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(0, 0, 0)}) {
    Quadricd q = random_quadric(rng);
    q.a = abc(0), q.b = abc(1), q.c = abc(2);
    const Eigen::Vector3d local = q.R * principal_direction(q);
    const Eigen::Vector3d expected =
        abc(0) < abc(2) ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    EXPECT_LT((local - expected).norm(), 1e-12) << abc.transpose();
  }
}

TEST(QuadricModel, LocalFrameIsRightHandedWithNormalAsThirdRow) {
  std::mt19937 rng(13);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d normal = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const Eigen::Matrix3d R = local_frame<double>(normal);
    EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_LT((R.row(2).transpose() - normal).norm(), 1e-12);
    if (std::abs(normal.x()) <= 0.9) {  // e_x: the camera x axis projected on the tangent plane
      EXPECT_GT(R(0, 0), 0.0);
    }
  }
}

TEST(QuadricModel, UpdateKeepsRotationOrthonormal) {
  std::mt19937 rng(17);
  Quadricd q = random_quadric(rng);
  std::normal_distribution<double> n(0.0, 0.3);
  for (int i = 0; i < 1000; ++i) {
    QuadricVector<double> d;
    d << n(rng), n(rng), 0, 0, 0, 0;
    apply_quadric_update(q, d);
  }
  EXPECT_LT((q.R * q.R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-11);
}

TEST(DenseCholesky, SolvesLikeEigenAndRejectsIndefinite) {
  std::mt19937 rng(19);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    Eigen::Matrix<double, 6, 6> M;
    for (int i = 0; i < 36; ++i)
      M(i) = n(rng);
    const Eigen::Matrix<double, 6, 6> H =
        M * M.transpose() + 0.1 * Eigen::Matrix<double, 6, 6>::Identity();
    Eigen::Matrix<double, 6, 1> b;
    for (int i = 0; i < 6; ++i)
      b(i) = n(rng);
    Eigen::Matrix<double, 6, 6> L = H;
    ASSERT_TRUE((cholesky_factor<double, 6>(L)));
    Eigen::Matrix<double, 6, 1> x = b;
    cholesky_solve<double, 6>(L, x);
    EXPECT_LT((H * x - b).norm(), 1e-10 * b.norm() * H.norm());
    // Several right-hand sides at once: each column as cholesky_solve gives it, to the bit.
    Eigen::Matrix<double, 6, 6> X = M;
    cholesky_solve_columns<double, 6, 6>(L, X);
    for (int c = 0; c < 6; ++c) {
      Eigen::Matrix<double, 6, 1> column = M.col(c);
      cholesky_solve<double, 6>(L, column);
      EXPECT_EQ(X.col(c), column) << "column " << c;
    }
    EXPECT_LT((H * X - M).norm(), 1e-10 * M.norm() * H.norm());
  }
  Eigen::Matrix<double, 6, 6> S = Eigen::Matrix<double, 6, 6>::Identity();
  S(3, 3) = -1.0;
  EXPECT_FALSE((cholesky_factor<double, 6>(S)));
  Eigen::Matrix<double, 6, 6> Z = Eigen::Matrix<double, 6, 6>::Identity();
  Z(2, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE((cholesky_factor<double, 6>(Z)));
}

}  // namespace
}  // namespace jpcr
