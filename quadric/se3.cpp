#include "jpcr/quadric/se3.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/SVD>

namespace jpcr {

namespace {

// Below this angle the coefficients come from their series (to θ⁴: the next terms are below
// 1e-16 relatively); above it the closed forms lose at most ~1e-11 to cancellation. With a
// cutoff of 1e-4, 1 − cos θ lost 2e-8 relatively just above it, and se3_log's d, a difference of
// such terms over θ², came out O(1) wrong: exp(log T) missed T by 1.8e-8 m per m of translation
// (review of 2026-12-06).
constexpr double kSeriesBelow = 1e-2;

// Coefficients of Rodrigues' formula and of V(ω) as functions of θ = |ω|; series near 0.
struct RodriguesCoefficients {
  double a;  // sin θ / θ
  double b;  // (1 − cos θ) / θ² = 2 sin²(θ/2) / θ², without the cancellation
  double c;  // (θ − sin θ) / θ³
};

RodriguesCoefficients rodrigues(double theta) {
  const double t2 = theta * theta, t4 = t2 * t2;
  if (theta < kSeriesBelow) {
    return {1.0 - t2 / 6.0 + t4 / 120.0, 0.5 - t2 / 24.0 + t4 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0};
  }
  const double s = std::sin(theta), half = std::sin(0.5 * theta);
  return {s / theta, 2.0 * half * half / t2, (theta - s) / (t2 * theta)};
}

}  // namespace

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return W;
}

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& w) {
  const RodriguesCoefficients k = rodrigues(w.norm());
  const Eigen::Matrix3d W = skew(w);
  return Eigen::Matrix3d::Identity() + k.a * W + k.b * W * W;
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d& R) {
  // Eigen's AngleAxis handles angles near π robustly; near 0 use the first-order form.
  const double cos_theta = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  const Eigen::Vector3d vee(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  if (cos_theta > 1.0 - 1e-10) return 0.5 * vee;  // θ < ~1.4e-5: log R ≈ (R − Rᵀ)∨ / 2
  if (cos_theta > -0.99) {
    const double theta = std::acos(cos_theta);
    return theta / (2.0 * std::sin(theta)) * vee;
  }
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Eigen::Isometry3d se3_exp(const Vector6d& xi) {
  const Eigen::Vector3d v = xi.head<3>(), w = xi.tail<3>();
  const RodriguesCoefficients k = rodrigues(w.norm());
  const Eigen::Matrix3d W = skew(w), W2 = W * W;
  const Eigen::Matrix3d V = Eigen::Matrix3d::Identity() + k.b * W + k.c * W2;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Matrix3d::Identity() + k.a * W + k.b * W2;
  T.translation() = V * v;
  return T;
}

Vector6d se3_log(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d w = so3_log(T.linear());
  const double theta = w.norm();
  const Eigen::Matrix3d W = skew(w);
  // V⁻¹ = I − W/2 + (1/θ²)(1 − a/(2b)) W², with a, b the Rodrigues coefficients.
  double d;
  if (theta < kSeriesBelow) {  // 1/θ² − cot(θ/2)/(2θ) = 1/12 + θ²/720 + θ⁴/30240 + …
    const double t2 = theta * theta;
    d = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0;
  } else {
    const RodriguesCoefficients k = rodrigues(theta);
    d = (1.0 - k.a / (2.0 * k.b)) / (theta * theta);
  }
  const Eigen::Matrix3d V_inv = Eigen::Matrix3d::Identity() - 0.5 * W + d * W * W;
  Vector6d xi;
  xi.head<3>() = V_inv * T.translation();
  xi.tail<3>() = w;
  return xi;
}

Matrix6d se3_adjoint(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  Matrix6d Ad = Matrix6d::Zero();
  Ad.topLeftCorner<3, 3>() = R;
  Ad.topRightCorner<3, 3>() = skew(T.translation()) * R;
  Ad.bottomRightCorner<3, 3>() = R;
  return Ad;
}

Matrix6d position_rotation_covariance(const Matrix6d& left_covariance, const Eigen::Vector3d& t) {
  Matrix6d J = Matrix6d::Identity();
  J.topRightCorner<3, 3>() = -skew(t);  // ω × t = −[t]× ω
  return J * left_covariance * J.transpose();
}

double rotation_angle(const Eigen::Matrix3d& R) {
  return so3_log(R).norm();
}

bool is_rigid(const Eigen::Isometry3d& T, double tolerance) {
  const Eigen::Matrix4d& M = T.matrix();
  if (!M.allFinite()) return false;
  if (M.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         R.determinant() > 0.0;
}

Eigen::Matrix3d orthonormalize(const Eigen::Matrix3d& R) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

Eigen::Isometry3d orthonormalized(const Eigen::Isometry3d& T) {
  Eigen::Isometry3d out = T;
  out.linear() = orthonormalize(T.linear());
  return out;
}

}  // namespace jpcr
