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

/// The eigenvector of the smallest eigenvalue of a symmetric 3x3 S and its eigenvalues,
/// ascending: the eigenvalues in closed form (with q = tr S / 3, p² = |S − q I|²_F / 6 and
/// r = det((S − q I) / p) / 2, φ = acos(r) / 3: λ_max = q + 2p cos φ, λ_min = q + 2p cos(φ + 2π/3),
/// λ_mid = 3q − λ_min − λ_max), the eigenvector as the longest cross product of two rows of
/// S − λ_min I, the other two eigenvectors being in their span. The method of Eigen's
/// computeDirect for the one eigenvector a plane fit needs. False where S is a multiple of I
/// or the cross products are at rounding level; at a double smallest eigenvalue (which this
/// closed form splits by about √ε) the answer is some unit vector of that eigenvalue's plane.
JPCR_HD bool smallest_eigenvector(const Eigen::Matrix3d& S, Eigen::Vector3d& n,
                                  Eigen::Vector3d& eigenvalues) {
  const double q = (S(0, 0) + S(1, 1) + S(2, 2)) / 3.0;
  Eigen::Matrix3d B = S;
  B.diagonal().array() -= q;
  const double p2 = (B(0, 0) * B(0, 0) + B(1, 1) * B(1, 1) + B(2, 2) * B(2, 2) +
                     2.0 * (S(0, 1) * S(0, 1) + S(0, 2) * S(0, 2) + S(1, 2) * S(1, 2))) /
                    6.0;
  if (!(p2 > 0.0)) return false;
  const double p = sqrt(p2);
  double r = B.determinant() / (2.0 * p2 * p);
  r = r < -1.0 ? -1.0 : (r > 1.0 ? 1.0 : r);
  const double phi = acos(r) / 3.0;
  const double largest = q + 2.0 * p * cos(phi);
  const double smallest = q + 2.0 * p * cos(phi + 2.0943951023931954923);  // + 2π/3
  eigenvalues = Eigen::Vector3d(smallest, 3.0 * q - smallest - largest, largest);
  B.diagonal().array() += q - smallest;  // S − λ_min I
  const Eigen::Vector3d r01 = B.row(0).cross(B.row(1)), r02 = B.row(0).cross(B.row(2)),
                        r12 = B.row(1).cross(B.row(2));
  const double n01 = r01.squaredNorm(), n02 = r02.squaredNorm(), n12 = r12.squaredNorm();
  const bool first = n01 >= n02 && n01 >= n12;
  const double longest = first ? n01 : (n02 >= n12 ? n02 : n12);
  // The cross products have length of order λ_mid λ_max (in S's units²); far below that they
  // are rounding.
  const double scale = eigenvalues(2) * eigenvalues(2);
  if (!(longest > 1e-20 * scale * scale)) return false;
  n = (first ? r01 : (n02 >= n12 ? r02 : r12)) / sqrt(longest);
  return true;
}

/// The normal of the least-squares plane through `count` points with Σ d = sum and
/// Σ d dᵀ = outer (d relative to any fixed origin): the eigenvector of the smallest eigenvalue
/// of the scatter matrix about their mean (smallest_eigenvector, or Eigen's computeDirect where
/// that is ill-posed, in double), oriented so that n·centre < 0. All-NaN when
/// count < p.min_points or the points are collinear.
JPCR_HD Eigen::Vector3f plane_normal_from_moments(const Eigen::Vector3d& sum,
                                                  const Eigen::Matrix3d& outer, int count,
                                                  const Eigen::Vector3f& centre,
                                                  const NormalEstimationParams& p) {
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  if (count < p.min_points) return none;
  const Eigen::Vector3d mean = sum / count;
  const Eigen::Matrix3d scatter = outer / count - mean * mean.transpose();
  Eigen::Vector3d ev, normal;
  if (!smallest_eigenvector(scatter, normal, ev)) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(scatter);
    ev = eig.eigenvalues();
    normal = eig.eigenvectors().col(0);
  }
  // Collinear points (a line of pixels) leave the plane undetermined.
  if (!(ev(1) > 1e-6 * ev(2)) || !(ev(0) - ev(0) == 0.0)) return none;
  Eigen::Vector3f n = normal.cast<float>().normalized();
  if (n.dot(centre) > 0.0f) n = -n;  // toward the camera
  return n;
}

/// The moments of the plane fit at (u, v): Σ d, Σ d dᵀ and the count of the window's valid
/// vertices X within the depth jump of the centre, with d = X − centre (centred for precision).
/// False where the centre has no vertex.
JPCR_HD bool window_moments(const VertexView& vertices, int u, int v,
                            const NormalEstimationParams& p, Eigen::Vector3d& sum,
                            Eigen::Matrix3d& outer, int& count) {
  sum.setZero();
  outer.setZero();
  count = 0;
  const Eigen::Vector3f centre = vertices(u, v);
  if (!is_sample_point(centre)) return false;
  const float jump = p.max_depth_jump * centre.z();
  for (int dv = -p.half_window; dv <= p.half_window; ++dv) {
    for (int du = -p.half_window; du <= p.half_window; ++du) {
      if (!vertices.in_bounds(u + du, v + dv)) continue;
      const Eigen::Vector3f& X = vertices(u + du, v + dv);
      if (!is_sample_point(X) || fabsf(X.z() - centre.z()) > jump) continue;
      const Eigen::Vector3d d = (X - centre).cast<double>();
      sum += d;
      outer += d * d.transpose();
      ++count;
    }
  }
  return true;
}

/// The plane normal at (u, v): the eigenvector of the smallest eigenvalue of the scatter matrix
/// of the window points about their mean (closed-form 3x3 solve, computeDirect, in double).
/// Unit, n·X < 0; all-NaN where the centre has no vertex, too few window points remain or the
/// points are collinear.
JPCR_HD Eigen::Vector3f plane_normal(const VertexView& vertices, int u, int v,
                                     const NormalEstimationParams& p) {
  Eigen::Vector3d sum;
  Eigen::Matrix3d outer;
  int count;
  if (!window_moments(vertices, u, v, p, sum, outer, count))
    return Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  return plane_normal_from_moments(sum, outer, count, vertices(u, v), p);
}

}  // namespace jpcr
