// Quad LS (method.md §4, after Douros & Buxton): the least-squares baseline Quad IT is measured
// against. In the initial normal frame at p̄, fit z = A x² + B x y + C y² + D x + E y + F to the
// pattern's samples, unweighted, without iteration or gate, and take κ₁, κ₂ as the eigenvalues
// of the shape operator I⁻¹ II at (0, 0).
#pragma once

#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {

/// The fitted height field z = A x² + B x y + C y² + D x + E y + F (local frame, metres).
struct HeightField {
  double A = 0, B = 0, C = 0, D = 0, E = 0, F = 0;
};

/// κ₁ ≥ κ₂ of a height field at (0, 0): eigenvalues of I⁻¹ II with
/// I = [[1 + D², DE], [DE, 1 + E²]] and II = [[2A, B], [B, 2C]] / √(1 + D² + E²).
Eigen::Vector2d height_field_curvatures(const HeightField& h);

/// The principal direction of κ₁ in the local frame (unit, tangent to the height field at 0).
Eigen::Vector3d height_field_direction(const HeightField& h);

class LeastSquaresQuadric final : public CurvatureEstimator {
 public:
  explicit LeastSquaresQuadric(const QuadricParams& params = {});
  using CurvatureEstimator::estimate;
  QuadricMap estimate(const VertexMap& vertices, const NormalMap& normals) const override;
  std::string name() const override { return "quad-ls"; }
  const QuadricParams& params() const override { return params_; }

 private:
  QuadricParams params_;
};

}  // namespace jpcr
