// The curvature peer of evaluation.md: CGAL's Monge jet fitting (libcgal-dev,
// CGAL::Monge_via_jet_fitting, Cazals & Pouget 2005) per pixel, on the same neighbourhood pattern
// as Quad IT and Quad LS, behind jpcr's CurvatureEstimator interface so that jpcr_curvature and
// jpcr_eval compare it on the same frames. Tools layer only: the core does not depend on CGAL.
#pragma once

#include <string>

#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr::peers {

/// A degree-2 jet (and Monge form) fitted by least squares to the valid pattern samples around
/// each pixel (no gate, no weights: CGAL's method as published), its normal oriented toward the
/// camera; κ₁ ≥ κ₂ in jpcr's sign convention (a sphere seen from outside: −1/R).
class CgalJetCurvature final : public CurvatureEstimator {
 public:
  explicit CgalJetCurvature(const QuadricParams& params = {}, int degree = 2);
  using CurvatureEstimator::estimate;
  QuadricMap estimate(const VertexMap& vertices, const NormalMap& normals) const override;
  std::string name() const override { return "cgal-jet"; }
  const QuadricParams& params() const override { return params_; }

 private:
  QuadricParams params_;
  int degree_;
};

}  // namespace jpcr::peers
