// The local quadric surface model of method.md §3, written once for the CPU and the GPU.
//
// A quadric γ_p lives at the centre point p̄ of pixel p, in a local frame R whose rows are
// (e_x, e_y, n) with n the surface normal toward the camera. A point X (camera frame of the
// quadric's image) has local coordinates
//
//     u = (x, y, z) = R (X − p̄) + t_z e₃,
//
// and the model surface is the height field z = ½ (a x² + 2 b x y + c y²). The residual
//
//     r(X; γ) = ½ (a x² + 2 b x y + c y²) − z
//
// is the (algebraic) distance along the local normal. The parameters are γ = (ω₁, ω₂, t_z, a, b,
// c): ω₁, ω₂ are small rotations about the local x and y axes applied as R ← exp([ω₁, ω₂, 0]×) R;
// rotation about n is a gauge freedom absorbed by b (method.md §3; the paper's "t_x" is t_z).
//
// Every function here is JPCR_HD (host + device under nvcc) and allocation-free, so the CPU
// reference (backend/, the tests) and the CUDA kernels (cuda/) call exactly the same code; the
// dense CPU Quad IT writes the same arithmetic on SIMD lanes (pixel_lane_sums.inc).
#pragma once

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "jpcr/quadric/host_device.hpp"

namespace jpcr {

/// One quadric γ_p with its local frame: R (rows e_x, e_y, n), the centre p̄ and (t_z, a, b, c).
template <typename Scalar>
struct QuadricT {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;

  Matrix3 R = Matrix3::Identity();   // rows e_x, e_y, n: world-of-the-image → local
  Vector3 center = Vector3::Zero();  // p̄, in the camera frame of the quadric's image (m)
  Scalar t_z = 0;                    // offset of the surface along n at p̄ (m)
  Scalar a = 0, b = 0, c = 0;        // second fundamental form coefficients (1/m)

  JPCR_HD Vector3 normal() const { return R.row(2).transpose(); }

  template <typename Other>
  JPCR_HD QuadricT<Other> cast() const {
    QuadricT<Other> q;
    q.R = R.template cast<Other>();
    q.center = center.template cast<Other>();
    q.t_z = static_cast<Other>(t_z);
    q.a = static_cast<Other>(a);
    q.b = static_cast<Other>(b);
    q.c = static_cast<Other>(c);
    return q;
  }
};

using Quadric = QuadricT<float>;
using Quadricd = QuadricT<double>;

/// The 6-vector γ = (ω₁, ω₂, t_z, a, b, c) and its Jacobians.
template <typename Scalar>
using QuadricVector = Eigen::Matrix<Scalar, 6, 1>;

/// The local frame of method.md §3 for a unit normal n (toward the camera): e_x is the camera x
/// axis projected onto the tangent plane, e_y = n × e_x. Near-degenerate n ≈ ±x falls back to
/// the camera y axis, so the frame is always orthonormal and right-handed.
template <typename Scalar>
JPCR_HD Eigen::Matrix<Scalar, 3, 3> local_frame(const Eigen::Matrix<Scalar, 3, 1>& n) {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  Vector3 axis = Vector3::UnitX();
  if (std::abs(n.x()) > Scalar(0.9)) axis = Vector3::UnitY();
  const Vector3 e_x = (axis - axis.dot(n) * n).normalized();
  const Vector3 e_y = n.cross(e_x);
  Eigen::Matrix<Scalar, 3, 3> R;
  R.row(0) = e_x.transpose();
  R.row(1) = e_y.transpose();
  R.row(2) = n.transpose();
  return R;
}

/// A residual with the pieces its Jacobians are built from.
template <typename Scalar>
struct QuadricLinearization {
  Scalar r = 0;                   // r(X; γ), m
  Eigen::Matrix<Scalar, 3, 1> v;  // R (X − p̄)
  Eigen::Matrix<Scalar, 3, 1> g;  // ∂r/∂u = (a x + b y, b x + c y, −1)
  QuadricVector<Scalar> J;        // ∂r/∂γ
};

/// r(X; γ) alone (method.md §3 "Model").
template <typename Scalar>
JPCR_HD Scalar quadric_residual(const QuadricT<Scalar>& q, const Eigen::Matrix<Scalar, 3, 1>& X) {
  const Eigen::Matrix<Scalar, 3, 1> v = q.R * (X - q.center);
  const Scalar x = v.x(), y = v.y(), z = v.z() + q.t_z;
  return Scalar(0.5) * (q.a * x * x + Scalar(2) * q.b * x * y + q.c * y * y) - z;
}

/// r and ∂r/∂γ (method.md §3 "Jacobian"): with v = R (X − p̄),
///   ∂r/∂γ = ( g·(0, −v_z, v_y), g·(v_z, 0, −v_x), −1, x²/2, x y, y²/2 ).
/// A quadric flattened to named scalars (R row-major), and one sample's residual and Jacobian in
/// named scalars: the form the CPU fit vectorises across samples (no arrays, no Eigen products,
/// no branches) and linearize_quadric wraps with Eigen types.
template <typename Scalar>
struct QuadricScalars {
  Scalar r00, r01, r02, r10, r11, r12, r20, r21, r22, t_z, a, b, c;

  JPCR_HD static QuadricScalars from(const QuadricT<Scalar>& q) {
    return {q.R(0, 0), q.R(0, 1), q.R(0, 2), q.R(1, 0), q.R(1, 1), q.R(1, 2), q.R(2, 0),
            q.R(2, 1), q.R(2, 2), q.t_z,     q.a,       q.b,       q.c};
  }
};

template <typename Scalar>
struct SampleLinearization {
  Scalar r;                       // r(X; γ)
  Scalar J0, J1, J2, J3, J4, J5;  // ∂r/∂γ
  Scalar vx, vy, vz;              // v = R (X − p̄)
  Scalar gx, gy;                  // g = (gx, gy, −1)
};

/// r and ∂r/∂γ for the sample d = X − p̄ (method.md §3).
template <typename Scalar>
JPCR_HD SampleLinearization<Scalar> linearize_sample(const QuadricScalars<Scalar>& q, Scalar dx,
                                                     Scalar dy, Scalar dz) {
  const Scalar vx = q.r00 * dx + q.r01 * dy + q.r02 * dz;
  const Scalar vy = q.r10 * dx + q.r11 * dy + q.r12 * dz;
  const Scalar vz = q.r20 * dx + q.r21 * dy + q.r22 * dz;
  const Scalar x = vx, y = vy, z = vz + q.t_z;
  const Scalar gx = q.a * x + q.b * y, gy = q.b * x + q.c * y;
  return {Scalar(0.5) * (gx * x + gy * y) - z,  // ½ (a x² + 2 b x y + c y²) − z
          -gy * vz - vy,                        // g·(0, −v_z, v_y)
          gx * vz + vx,                         // g·(v_z, 0, −v_x)
          Scalar(-1),
          Scalar(0.5) * x * x,
          x * y,
          Scalar(0.5) * y * y,
          vx,
          vy,
          vz,
          gx,
          gy};
}

template <typename Scalar>
JPCR_HD QuadricLinearization<Scalar> linearize_quadric(const QuadricT<Scalar>& q,
                                                       const Eigen::Matrix<Scalar, 3, 1>& X) {
  const SampleLinearization<Scalar> s =
      linearize_sample(QuadricScalars<Scalar>::from(q), X.x() - q.center.x(), X.y() - q.center.y(),
                       X.z() - q.center.z());
  QuadricLinearization<Scalar> l;
  l.r = s.r;
  l.v = Eigen::Matrix<Scalar, 3, 1>(s.vx, s.vy, s.vz);
  l.g = Eigen::Matrix<Scalar, 3, 1>(s.gx, s.gy, Scalar(-1));
  l.J << s.J0, s.J1, s.J2, s.J3, s.J4, s.J5;
  return l;
}

/// The lever-arm moment m = v × g of a sample, whose first two entries are the tilt entries J₀, J₁
/// of ∂r/∂γ and which enters the rotation entries of the pose Jacobian (v × g = R (X − p̄) × g),
/// evaluated at the foot point instead of the sample: the point where the sample's viewing ray
/// meets the quadric, to first order. With ρ = R (X − o) the ray from the sample's camera
/// centre o in local axes, the foot point is v_s = v − (r / g·ρ) ρ, so
///
///     m_s = v_s × g = v × g − (r / g·ρ) (ρ × g).
///
/// Why: a range sensor's error lies along the ray, so at the sample the lever arm moves with the
/// very error that makes the residual, and Σ w J r of the normal equations has a non-zero mean
/// at the true pose; at the foot point the lever arm does not move with it (exactly so on a
/// plane). Where the ray grazes the surface (g·ρ)² < cos²_min |g|² |ρ|², the foot point is far
/// and ill-defined: the sample keeps its own lever arm, and with cos²_min = kNoRayFoot (> 1)
/// every sample does. Branch-free for the SIMD loops.
constexpr double kNoRayFoot = 2.0;

template <typename Scalar>
JPCR_HD void ray_foot_moment(Scalar r, Scalar vx, Scalar vy, Scalar vz, Scalar gx, Scalar gy,
                             Scalar rho_x, Scalar rho_y, Scalar rho_z, Scalar min_cos2, Scalar& m0,
                             Scalar& m1, Scalar& m2) {
  const Scalar g_rho = gx * rho_x + gy * rho_y - rho_z;  // g = (g_x, g_y, −1)
  const Scalar g2 = gx * gx + gy * gy + Scalar(1);
  const Scalar rho2 = rho_x * rho_x + rho_y * rho_y + rho_z * rho_z;
  const bool along = g_rho * g_rho >= min_cos2 * g2 * rho2 && rho2 > Scalar(0);
  const Scalar denominator = along ? g_rho : Scalar(1);
  const Scalar s = along ? r / denominator : Scalar(0);
  m0 = -vy - vz * gy - s * (-rho_y - rho_z * gy);  // (v × g)_x − s (ρ × g)_x
  m1 = vz * gx + vx - s * (rho_z * gx + rho_x);    // (v × g)_y − s (ρ × g)_y
  m2 = vx * gy - vy * gx - s * (rho_x * gy - rho_y * gx);
}

/// ∂r/∂ξ of a residual whose point is X = T Q, under the left update T ← exp(ξ^) T with
/// ξ = (v, ω) (method.md §6 "Pose Jacobian"): with g_w = Rᵀ g, J_ξ = [g_wᵀ, (X × g_w)ᵀ].
template <typename Scalar>
JPCR_HD Eigen::Matrix<Scalar, 6, 1> quadric_pose_jacobian(const QuadricT<Scalar>& q,
                                                          const QuadricLinearization<Scalar>& l,
                                                          const Eigen::Matrix<Scalar, 3, 1>& X) {
  const Eigen::Matrix<Scalar, 3, 1> g_w = q.R.transpose() * l.g;
  Eigen::Matrix<Scalar, 6, 1> J;
  J.template head<3>() = g_w;
  J.template tail<3>() = X.cross(g_w);
  return J;
}

/// The modified "fair" weight of method.md §3: w = n₀² / (n₀² + r² + d²), d = |X − p̄|.
template <typename Scalar>
JPCR_HD Scalar fair_weight(Scalar r, Scalar d2, Scalar n0) {
  const Scalar n02 = n0 * n0;
  return n02 / (n02 + r * r + d2);
}

/// γ ← γ ⊕ Δγ: R ← exp([Δω₁, Δω₂, 0]×) R (Rodrigues, exact), then t_z, a, b, c added.
template <typename Scalar>
JPCR_HD void apply_quadric_update(QuadricT<Scalar>& q, const QuadricVector<Scalar>& delta) {
  const Scalar w1 = delta(0), w2 = delta(1);
  const Scalar theta2 = w1 * w1 + w2 * w2;
  if (theta2 > Scalar(0)) {
    const Scalar theta = std::sqrt(theta2);
    const Scalar s = std::sin(theta) / theta;
    const Scalar k = (Scalar(1) - std::cos(theta)) / theta2;
    Eigen::Matrix<Scalar, 3, 3> W;
    W << Scalar(0), Scalar(0), w2, Scalar(0), Scalar(0), -w1, -w2, w1, Scalar(0);
    const Eigen::Matrix<Scalar, 3, 3> Rw =
        Eigen::Matrix<Scalar, 3, 3>::Identity() + s * W + k * W * W;
    // exp([ω]×) acts on local coordinates: u' = Rw u, so the rows update as R ← Rw R.
    q.R = Rw * q.R;
  }
  q.t_z += delta(2);
  q.a += delta(3);
  q.b += delta(4);
  q.c += delta(5);
}

/// Principal curvatures (κ₁ ≥ κ₂) of K = [[a, b], [b, c]] (method.md §3 "Output"):
/// t₁ = (a + c)/2, t₂ = √(t₁² − ac + b²), κ = t₁ ± t₂.
template <typename Scalar>
JPCR_HD Eigen::Matrix<Scalar, 2, 1> principal_curvatures(Scalar a, Scalar b, Scalar c) {
  const Scalar t1 = Scalar(0.5) * (a + c);
  const Scalar h = Scalar(0.5) * (a - c);
  const Scalar t2 = std::sqrt(h * h + b * b);  // = √(t₁² − ac + b²), without cancellation
  return Eigen::Matrix<Scalar, 2, 1>(t1 + t2, t1 - t2);
}

/// The first principal direction (of κ₁) in the camera frame: φ = ½ atan2(2b, a − c),
/// d₁ = cos φ e_x + sin φ e_y; d₂ = n × d₁. Without trigonometry: with h = (a − c)/2 and
/// ρ = √(h² + b²), cos 2φ = h/ρ and sin 2φ = b/ρ, and the half angle is taken from whichever of
/// cos φ = √((ρ + h)/2ρ) (h ≥ 0) or |sin φ| = √((ρ − h)/2ρ) (h < 0) has no cancellation, the
/// other from 2 sin φ cos φ = b/ρ; φ ∈ (−π/2, π/2], so cos φ ≥ 0 and sin φ has the sign of b.
/// At an umbilic (ρ = 0) every direction is principal: d₁ = e_x.
template <typename Scalar>
JPCR_HD Eigen::Matrix<Scalar, 3, 1> principal_direction(const QuadricT<Scalar>& q) {
  const Scalar h = Scalar(0.5) * (q.a - q.c), b = q.b;
  const Scalar rho = std::sqrt(h * h + b * b);
  Scalar c = Scalar(1), s = Scalar(0);
  if (rho > Scalar(0)) {
    if (h >= Scalar(0)) {
      c = std::sqrt((rho + h) / (Scalar(2) * rho));
      s = b / (Scalar(2) * rho * c);
    } else {
      s = std::sqrt((rho - h) / (Scalar(2) * rho));
      s = b < Scalar(0) ? -s : s;
      c = b / (Scalar(2) * rho * s);
    }
  }
  return (c * q.R.row(0) + s * q.R.row(1)).transpose();
}

}  // namespace jpcr
