#include "jpcr/quadric/quadric_fit.hpp"

#include <stdexcept>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

void PatternParams::validate() const {
  if (radius < 1 || radius > 64) throw InputError("radius: must be in [1, 64]");
  if (stride < 1 || stride > 64) throw InputError("stride: must be in [1, 64]");
  if (reference_width < 1) throw InputError("reference_width: must be positive (px)");
}

void QuadricFitParams::validate() const {
  if (iterations < 1 || iterations > 100) throw InputError("iterations: must be in [1, 100]");
  if (!(fair_n0 > 0.0f)) throw InputError("fair_n0: must be positive (m)");
  if (!(residual_gate > 0.0f)) throw InputError("residual_gate: must be positive (m)");
  if (!(fair_n0_per_range >= 0.0f)) throw InputError("fair_n0_per_range: must be >= 0 (m/m)");
  if (!(gate_per_range >= 0.0f)) throw InputError("gate_per_range: must be >= 0 (m/m)");
  if (!(damping >= 0.0f)) throw InputError("damping: must be >= 0");
  if (min_samples < 6) throw InputError("min_samples: must be at least 6 (six parameters)");
  if (!(angle_tolerance >= 0.0f)) throw InputError("angle_tolerance: must be >= 0 (rad)");
  if (!(offset_tolerance >= 0.0f)) throw InputError("offset_tolerance: must be >= 0 (m)");
  if (!(curvature_tolerance >= 0.0f)) throw InputError("curvature_tolerance: must be >= 0 (1/m)");
}

void QuadricParams::validate() const {
  pattern.validate();
  normals.validate();
  fit.validate();
}

QuadricMap CurvatureEstimator::estimate(const VertexMap& vertices) const {
  return estimate(vertices, estimate_normals(vertices, params().normals));
}

QuadricFit::QuadricFit(const QuadricParams& params) : params_(params) {
  params_.validate();
}

QuadricMap QuadricFit::estimate(const VertexMap& vertices, const NormalMap& normals) const {
  if (normals.width() != vertices.width() || normals.height() != vertices.height())
    throw std::invalid_argument("QuadricFit: normal map and vertex map differ in size");
  const NeighbourhoodPattern pattern = params_.pattern.for_width(vertices.width());
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  QuadricMap map(vertices.width(), vertices.height());
#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < vertices.height(); ++v) {
    for (int u = 0; u < vertices.width(); ++u) {
      Quadricd q;
      const QuadricStatus status = fit_quadric_pixel<double>(
          view, pattern.offsets.data(), pattern.size(), u, v, normals(u, v), params_.fit, q);
      if (status == QuadricStatus::kValid)
        map.set(u, v, q.cast<float>());
      else
        map.set_invalid(u, v, status);
    }
  }
  return map;
}

}  // namespace jpcr
