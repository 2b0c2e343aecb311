// The initial normal of one pixel (method.md §3): a least-squares plane through the valid
// vertices of its (2h+1)x(2h+1) window, oriented toward the camera. JPCR_HD and allocation-free,
// so estimate_normals (surface_normals.cpp) and the CUDA Quad IT (cuda/) run exactly this code.
#pragma once

#include <limits>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "jpcr/quadric/quadric_fit_kernel.hpp"
#include "jpcr/quadric/surface_normals.hpp"

namespace jpcr {

/// The normal of the least-squares plane through `count` points with Σ d = sum and
/// Σ d dᵀ = outer (d relative to any fixed origin): the eigenvector of the smallest eigenvalue
/// of the scatter matrix about their mean (closed-form 3x3 solve, computeDirect, in double),
/// oriented so that n·centre < 0. All-NaN when count < p.min_points or the points are collinear.
JPCR_HD Eigen::Vector3f plane_normal_from_moments(const Eigen::Vector3d& sum,
                                                  const Eigen::Matrix3d& outer, int count,
                                                  const Eigen::Vector3f& centre,
                                                  const NormalEstimationParams& p) {
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  if (count < p.min_points) return none;
  const Eigen::Vector3d mean = sum / count;
  const Eigen::Matrix3d scatter = outer / count - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(scatter);
  const Eigen::Vector3d ev = eig.eigenvalues();
  // Collinear points (a line of pixels) leave the plane undetermined.
  if (!(ev(1) > 1e-6 * ev(2)) || !(ev(0) - ev(0) == 0.0)) return none;
  Eigen::Vector3f n = eig.eigenvectors().col(0).cast<float>().normalized();
  if (n.dot(centre) > 0.0f) n = -n;  // toward the camera
  return n;
}

/// The plane normal at (u, v): the eigenvector of the smallest eigenvalue of the scatter matrix
/// of the window points about their mean (closed-form 3x3 solve, computeDirect, in double).
/// Unit, n·X < 0; all-NaN where the centre has no vertex, too few window points remain or the
/// points are collinear.
JPCR_HD Eigen::Vector3f plane_normal(const VertexView& vertices, int u, int v,
                                     const NormalEstimationParams& p) {
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  const Eigen::Vector3f centre = vertices(u, v);
  if (!is_finite_value(centre.z())) return none;
  const float jump = p.max_depth_jump * centre.z();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int count = 0;
  for (int dv = -p.half_window; dv <= p.half_window; ++dv) {
    for (int du = -p.half_window; du <= p.half_window; ++du) {
      if (!vertices.in_bounds(u + du, v + dv)) continue;
      const Eigen::Vector3f& X = vertices(u + du, v + dv);
      if (!is_finite_value(X.z()) || fabsf(X.z() - centre.z()) > jump) continue;
      const Eigen::Vector3d d = (X - centre).cast<double>();  // centred for precision
      sum += d;
      outer += d * d.transpose();
      ++count;
    }
  }
  return plane_normal_from_moments(sum, outer, count, centre, p);
}

}  // namespace jpcr
