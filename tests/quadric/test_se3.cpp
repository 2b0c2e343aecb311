// Property tests of the SE(3) helpers (Sophus style): exp/log round trips, the adjoint identity,
// and the small-angle series against the closed forms.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

Vector6d random_twist(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0.0, scale);
  Vector6d xi;
  for (int i = 0; i < 6; ++i)
    xi[i] = n(rng);
  return xi;
}

TEST(Se3, ExpLogRoundTripOverManyScales) {
  std::mt19937 rng(7);
  for (double scale : {1e-9, 1e-6, 1e-3, 0.1, 0.5, 1.0}) {
    for (int k = 0; k < 200; ++k) {
      Vector6d xi = random_twist(rng, scale);
      if (xi.tail<3>().norm() > 3.0) continue;  // stay below π so log is unique
      const Vector6d back = se3_log(se3_exp(xi));
      EXPECT_LT((back - xi).norm(), 1e-10 * std::max(1.0, xi.norm())) << "scale " << scale;
    }
  }
}

// Around the switch from series to closed forms, with a translation of a metre: exp(log T) = T
// to rounding. The closed form of (1 − cos θ)/θ² lost 2e-8 relatively just above the old switch
// at 1e-4, which made se3_log's d O(1) wrong there: 1.8e-8 m.
TEST(Se3, ExpLogRoundTripIsExactAcrossTheSeriesSwitch) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (double angle : {0.99e-4, 1.0001e-4, 3e-4, 1e-3, 0.99e-2, 1.0001e-2, 3e-2}) {
    for (int k = 0; k < 50; ++k) {
      Vector6d xi;
      xi.head<3>() = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      xi.tail<3>() = angle * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      const Eigen::Isometry3d T = se3_exp(xi);
      EXPECT_LT((se3_exp(se3_log(T)).matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-13)
          << "angle " << angle;
      EXPECT_LT((se3_log(T) - xi).norm(), 1e-12) << "angle " << angle;
    }
  }
}

TEST(Se3, LogExpRoundTripNearPi) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -0.5).normalized();
  for (double angle : {M_PI - 1e-3, M_PI - 1e-7, M_PI}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const Eigen::Vector3d w = so3_log(R);
    EXPECT_NEAR(w.norm(), angle, 1e-6);
    EXPECT_LT((so3_exp(w) - R).norm(), 1e-9);
  }
}

TEST(Se3, ExpMatchesEigenAngleAxis) {
  const Eigen::Vector3d w(0.3, -0.2, 0.9);
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  EXPECT_LT((so3_exp(w) - expected).norm(), 1e-14);
}

TEST(Se3, PureTranslationTwist) {
  Vector6d xi = Vector6d::Zero();
  xi.head<3>() << 0.1, -0.2, 0.3;
  const Eigen::Isometry3d T = se3_exp(xi);
  EXPECT_LT((T.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_LT((T.translation() - xi.head<3>()).norm(), 1e-15);
}

TEST(Se3, AdjointConjugatesTwists) {
  std::mt19937 rng(11);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Isometry3d T = se3_exp(random_twist(rng, 0.7));
    const Vector6d xi = random_twist(rng, 0.3);
    const Eigen::Isometry3d lhs = T * se3_exp(xi) * T.inverse();
    const Eigen::Isometry3d rhs = se3_exp(se3_adjoint(T) * xi);
    EXPECT_LT((lhs.matrix() - rhs.matrix()).norm(), 1e-12);
  }
}

TEST(Se3, LeftUpdateDerivativeIsTheGenerator) {
  // d/dε exp(ε e_i) T X at ε = 0 equals (v part) e_i, (ω part) e_i × (T X): the point-to-plane
  // Jacobian [nᵀ, (TX × n)ᵀ] of method.md §5 rests on this.
  const Eigen::Isometry3d T = se3_exp((Vector6d() << 0.1, 0.2, -0.1, 0.3, -0.2, 0.1).finished());
  const Eigen::Vector3d X(0.4, -0.3, 1.7), TX = T * X;
  const double h = 1e-7;
  for (int i = 0; i < 6; ++i) {
    Vector6d e = Vector6d::Zero();
    e[i] = h;
    const Eigen::Vector3d numeric = ((se3_exp(e) * T) * X - (se3_exp(-e) * T) * X) / (2 * h);
    Eigen::Vector3d analytic = Eigen::Vector3d::Zero();
    if (i < 3)
      analytic[i] = 1.0;
    else
      analytic = Eigen::Vector3d::Unit(i - 3).cross(TX);
    EXPECT_LT((numeric - analytic).norm(), 1e-7) << "generator " << i;
  }
}

// position_rotation_covariance against sampling: ξ ~ N(0, Σ) (mm, mrad) applied as exp(ξ^) T to
// a pose 2 m from the origin, where the rotation's lever arm dominates the position error. 20000
// draws estimate a variance to about 1 % (√(2/N)); second-order terms are ~1e-3 relative.
TEST(Se3, PositionRotationCovarianceMatchesSampledLeftUpdates) {
  std::mt19937 rng(3);
  const Eigen::Isometry3d T = se3_exp((Vector6d() << 1.5, -1.0, 0.8, 0.3, -0.2, 0.5).finished());
  Matrix6d L = Matrix6d::Zero();  // Σ = L Lᵀ, correlated
  L.diagonal() << 2e-3, 1e-3, 3e-3, 1e-3, 2e-3, 1.5e-3;
  L(4, 1) = 0.7e-3;
  L(5, 0) = -0.5e-3;
  const Matrix6d sigma = L * L.transpose();
  const Matrix6d predicted = position_rotation_covariance(sigma, T.translation());
  std::normal_distribution<double> n(0.0, 1.0);
  const int draws = 20000;
  Matrix6d sampled = Matrix6d::Zero();
  for (int i = 0; i < draws; ++i) {
    Vector6d z;
    for (int k = 0; k < 6; ++k)
      z[k] = n(rng);
    const Eigen::Isometry3d Tp = se3_exp(L * z) * T;
    Vector6d e;
    e.head<3>() = Tp.translation() - T.translation();
    e.tail<3>() = so3_log(Tp.linear() * T.linear().transpose());
    sampled += e * e.transpose() / draws;
  }
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(sampled(i, i) / predicted(i, i), 1.0, 0.04) << "axis " << i;
    // Without the lever arm the position's variance would be sigma(i, i), far off at 2 m.
    if (i < 3) {
      EXPECT_GT(predicted(i, i), 1.5 * sigma(i, i)) << "axis " << i;
    }
  }
  const Eigen::Matrix<double, 6, 1> d = predicted.diagonal().cwiseSqrt().cwiseInverse();
  EXPECT_LT((d.asDiagonal() * (sampled - predicted) * d.asDiagonal()).cwiseAbs().maxCoeff(), 0.04);
}

TEST(Se3, RotationAngleIsAccurateForTinyAngles) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1e-9, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_NEAR(rotation_angle(R), 1e-9, 1e-15);
}

TEST(Se3, OrthonormalizeRestoresRotation) {
  Eigen::Matrix3d R = so3_exp(Eigen::Vector3d(0.2, 0.1, -0.4));
  const Eigen::Matrix3d noisy = R + 1e-4 * Eigen::Matrix3d::Ones();
  const Eigen::Matrix3d fixed = orthonormalize(noisy);
  EXPECT_LT((fixed * fixed.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(fixed.determinant(), 1.0, 1e-12);
  EXPECT_LT((fixed - R).norm(), 1e-3);
}

TEST(Se3, IsRigidAcceptsMotionsAndRefusesScaleShearReflectionAndNan) {
  Vector6d xi;
  xi << 0.3, -0.2, 1.5, 0.4, -1.1, 2.0;
  Eigen::Isometry3d T(se3_exp(xi));
  EXPECT_TRUE(is_rigid(T));
  EXPECT_TRUE(is_rigid(Eigen::Isometry3d::Identity()));
  Eigen::Isometry3d scaled = T;
  scaled.linear() *= 1.001;  // RᵀR off by 2e-3
  EXPECT_FALSE(is_rigid(scaled));
  Eigen::Isometry3d sheared = T;
  sheared.linear()(0, 1) += 1e-4;
  EXPECT_FALSE(is_rigid(sheared));
  Eigen::Isometry3d drifted = T;  // what many composed updates leave: inside the tolerance
  drifted.linear() *= 1.0 + 1e-8;
  EXPECT_TRUE(is_rigid(drifted));
  Eigen::Isometry3d mirrored = T;
  mirrored.linear().col(2) *= -1.0;
  EXPECT_FALSE(is_rigid(mirrored));
  Eigen::Isometry3d nan = T;
  nan.translation().x() = std::nan("");
  EXPECT_FALSE(is_rigid(nan));
  Eigen::Isometry3d projective = T;
  projective.matrix()(3, 0) = 1e-3;
  EXPECT_FALSE(is_rigid(projective));
}

}  // namespace
}  // namespace jpcr
