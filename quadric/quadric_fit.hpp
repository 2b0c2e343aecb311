// Dense per-pixel curvature estimation from one frame: Quad IT (QuadricFit, method.md §3, the
// 2015 iterative fit that also initialises J-ftf and J-full) and Quad LS (LeastSquaresQuadric,
// method.md §4, in least_squares_quadric.hpp). Both run in parallel over pixels on the CPU; the
// CUDA Quad IT (cuda/) implements the same interface.
#pragma once

#include <string>

#include "jpcr/quadric/quadric_map.hpp"
#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr {

/// One frame's vertex map in, one QuadricMap out.
class CurvatureEstimator {
 public:
  virtual ~CurvatureEstimator() = default;
  /// The initial normals are estimated here (surface_normals.hpp) unless given; virtual so that
  /// the CUDA estimator can compute them on the device.
  virtual QuadricMap estimate(const VertexMap& vertices) const;
  virtual QuadricMap estimate(const VertexMap& vertices, const NormalMap& normals) const = 0;
  virtual std::string name() const = 0;
  virtual const QuadricParams& params() const = 0;
};

/// Quad IT: weighted Gauss-Newton per pixel (quadric_fit_kernel.hpp).
class QuadricFit final : public CurvatureEstimator {
 public:
  explicit QuadricFit(const QuadricParams& params = {});
  using CurvatureEstimator::estimate;
  QuadricMap estimate(const VertexMap& vertices, const NormalMap& normals) const override;
  std::string name() const override { return "quad-it"; }
  const QuadricParams& params() const override { return params_; }

 private:
  QuadricParams params_;
};

}  // namespace jpcr
