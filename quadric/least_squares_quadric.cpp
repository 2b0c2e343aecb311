#include "jpcr/quadric/least_squares_quadric.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "jpcr/quadric/quadric_fit_kernel.hpp"

namespace jpcr {

namespace {

// The shape operator S = I⁻¹ II of a height field at (0, 0).
Eigen::Matrix2d shape_operator(const HeightField& h) {
  Eigen::Matrix2d I, II;
  I << 1.0 + h.D * h.D, h.D * h.E, h.D * h.E, 1.0 + h.E * h.E;
  II << 2.0 * h.A, h.B, h.B, 2.0 * h.C;
  II /= std::sqrt(1.0 + h.D * h.D + h.E * h.E);
  return I.inverse() * II;  // I is positive definite (det = 1 + D² + E²)
}

// Fits the height field to the samples around (u, v), in the frame R at p̄. The coordinates are
// scaled by 1/ρ (ρ = RMS radius of the samples) so the 6x6 normal equations are well conditioned.
// Returns kValid, kTooFewSamples, or kSingular (e.g. all samples on one line).
QuadricStatus fit_height_field(const VertexMap& vertices, const NeighbourhoodPattern& pattern,
                               int u, int v, const Eigen::Matrix3d& R,
                               const Eigen::Vector3d& centre, int min_samples, HeightField& h) {
  // Two passes over the samples: the scale first, then the scaled normal equations.
  auto for_each_sample = [&](auto&& f) {
    for (const PixelOffset& o : pattern.offsets) {
      if (!vertices.in_bounds(u + o.du, v + o.dv)) continue;
      const Eigen::Vector3f& X = vertices(u + o.du, v + o.dv);
      if (is_sample_point(X)) f(Eigen::Vector3d(R * (X.cast<double>() - centre)));
    }
  };
  int n = 0;
  double radius2 = 0.0;
  for_each_sample([&](const Eigen::Vector3d& l) {
    radius2 += l.head<2>().squaredNorm();
    ++n;
  });
  if (n < min_samples) return QuadricStatus::kTooFewSamples;
  if (!(radius2 > 0.0)) return QuadricStatus::kSingular;
  const double k = 1.0 / std::sqrt(radius2 / n);
  Eigen::Matrix<double, 6, 6> AtA = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> Atz = Eigen::Matrix<double, 6, 1>::Zero();
  for_each_sample([&](const Eigen::Vector3d& l) {
    const double x = l.x() * k, y = l.y() * k, z = l.z() * k;
    Eigen::Matrix<double, 6, 1> row;
    row << x * x, x * y, y * y, x, y, 1.0;
    AtA.selfadjointView<Eigen::Lower>().rankUpdate(row);
    Atz += row * z;
  });
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(AtA.selfadjointView<Eigen::Lower>());
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return QuadricStatus::kSingular;
  const Eigen::Matrix<double, 6, 1> s = ldlt.solve(Atz);
  // Rank deficiency (e.g. all samples on one line) shows up as a non-finite or huge solution.
  if (!s.allFinite() || ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff())
    return QuadricStatus::kSingular;
  // Undo the scaling: z k = A' (k x)² + ... ⇒ A = A' k, D = D', F = F' / k.
  h = HeightField{s(0) * k, s(1) * k, s(2) * k, s(3), s(4), s(5) / k};
  return QuadricStatus::kValid;
}

}  // namespace

Eigen::Vector2d height_field_curvatures(const HeightField& h) {
  const Eigen::Matrix2d S = shape_operator(h);
  // S is self-adjoint w.r.t. I, so its eigenvalues are real: κ = H ± √(H² − K).
  const double H = 0.5 * S.trace(), K = S.determinant();
  const double root = std::sqrt(std::max(0.0, H * H - K));
  return Eigen::Vector2d(H + root, H - root);
}

Eigen::Vector3d height_field_direction(const HeightField& h) {
  const Eigen::Matrix2d S = shape_operator(h);
  const double k1 = height_field_curvatures(h).x();
  // (S − κ₁ I) w = 0: take the better conditioned of the two rows' null vectors.
  Eigen::Vector2d w(S(0, 1), k1 - S(0, 0));
  const Eigen::Vector2d w2(k1 - S(1, 1), S(1, 0));
  if (w2.squaredNorm() > w.squaredNorm()) w = w2;
  if (w.squaredNorm() < 1e-24) w = Eigen::Vector2d::UnitX();  // umbilic: any direction
  const Eigen::Vector3d t = w.x() * Eigen::Vector3d(1, 0, h.D) + w.y() * Eigen::Vector3d(0, 1, h.E);
  return t.normalized();
}

LeastSquaresQuadric::LeastSquaresQuadric(const QuadricParams& params) : params_(params) {
  params_.validate();
}

QuadricMap LeastSquaresQuadric::estimate(const VertexMap& vertices,
                                         const NormalMap& normals) const {
  if (normals.width() != vertices.width() || normals.height() != vertices.height())
    throw std::invalid_argument("LeastSquaresQuadric: normal map and vertex map differ in size");
  const NeighbourhoodPattern pattern = params_.pattern_for(vertices.width());
  QuadricMap map(vertices.width(), vertices.height());
#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < vertices.height(); ++v) {
    for (int u = 0; u < vertices.width(); ++u) {
      if (!is_sample_point(vertices(u, v))) {
        map.set_invalid(u, v, QuadricStatus::kNoCentre);
        continue;
      }
      if (!is_valid(normals(u, v))) {
        map.set_invalid(u, v, QuadricStatus::kNoNormal);
        continue;
      }
      const Eigen::Matrix3d R = local_frame<double>(normals(u, v).cast<double>().normalized());
      const Eigen::Vector3d centre = vertices(u, v).cast<double>();
      HeightField h;
      const QuadricStatus fitted =
          fit_height_field(vertices, pattern, u, v, R, centre, params_.fit.min_samples, h);
      if (fitted != QuadricStatus::kValid) {
        map.set_invalid(u, v, fitted);
        continue;
      }
      Quadricd q;  // the record keeps the second-order terms; curvature comes from I⁻¹ II
      q.R = R;
      q.center = centre;
      q.t_z = -h.F;
      q.a = 2.0 * h.A;
      q.b = h.B;
      q.c = 2.0 * h.C;
      const Eigen::Vector3d d1 = R.transpose() * height_field_direction(h);
      map.set(u, v, q.cast<float>(), height_field_curvatures(h).cast<float>(), d1.cast<float>());
    }
  }
  return map;
}

}  // namespace jpcr
