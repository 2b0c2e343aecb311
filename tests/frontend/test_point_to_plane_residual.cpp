// The point-to-plane residual e = nᵀ(T X − q) and its Jacobian [nᵀ, (T X × n)ᵀ] against central
// finite differences of e(exp(δ eᵢ^) T) (method.md §5, left-multiplicative update of §1).
#include <random>

#include <gtest/gtest.h>

#include "jpcr/frontend/normal_equations.hpp"
#include "jpcr/frontend/point_to_plane_residual.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {
namespace {

using Residual = PointToPlaneResidual<double>;

Vector6d random_twist(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Vector6d xi;
  for (int i = 0; i < 6; ++i)
    xi[i] = u(rng);
  return xi;
}

TEST(PointToPlaneResidual, JacobianMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr double h = 1e-6;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Isometry3d T = se3_exp(random_twist(rng, 0.5));
    const Eigen::Vector3d X(u(rng), u(rng), 2.0 + u(rng));
    const Eigen::Vector3d q(u(rng), u(rng), 2.0 + u(rng));
    const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), -1.0).normalized();
    const Vector6d J = Residual::jacobian(T * X, n);
    for (int i = 0; i < 6; ++i) {
      const Vector6d d = Vector6d::Unit(i) * h;
      const double plus = Residual::error(se3_exp(d) * T * X, q, n);
      const double minus = Residual::error(se3_exp(-d) * T * X, q, n);
      // Central differences of a function whose second derivative is O(|X|): error O(h²).
      EXPECT_NEAR(J[i], (plus - minus) / (2.0 * h), 1e-8) << "trial " << trial << " column " << i;
    }
  }
}

TEST(PointToPlaneResidual, ErrorIsTheSignedDistanceToTheTangentPlane) {
  const Eigen::Vector3d q(0.1, 0.2, 1.5), n(0.0, 0.0, -1.0);
  EXPECT_DOUBLE_EQ(Residual::error(q, q, n), 0.0);
  EXPECT_DOUBLE_EQ(Residual::error(q + Eigen::Vector3d(0.3, -0.2, 0.0), q, n), 0.0);  // in-plane
  EXPECT_DOUBLE_EQ(Residual::error(q + Eigen::Vector3d(0.0, 0.0, 0.25), q, n), -0.25);
}

TEST(NormalEquations, UpperTriangleAndGradientMatchDenseSums) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  NormalEquations a, b;
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  for (int k = 0; k < 50; ++k) {
    Eigen::Matrix<float, 6, 1> J;
    for (int i = 0; i < 6; ++i)
      J[i] = u(rng);
    const float e = u(rng), w = 0.5f + 0.5f * u(rng);
    (k % 2 ? a : b).add(J, e, w);
    H += static_cast<double>(w) * J.cast<double>() * J.cast<double>().transpose();
    g += static_cast<double>(w) * static_cast<double>(e) * J.cast<double>();
  }
  a += b;
  EXPECT_EQ(a.inliers, 50u);
  EXPECT_LT((a.hessian() - H).norm(), 1e-12 * H.norm());
  EXPECT_LT((a.gradient() - g).norm(), 1e-12 * g.norm());
}

}  // namespace
}  // namespace jpcr
