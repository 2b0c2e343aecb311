#include "jpcr/quadric/surface_normals.hpp"

#include <cmath>
#include <string>

#include <Eigen/Eigenvalues>

#include "jpcr/quadric/error.hpp"

namespace jpcr {

namespace {

// The plane normal at (u, v): the eigenvector of the smallest eigenvalue of the scatter matrix
// of the window points about their mean.
Eigen::Vector3f plane_normal(const VertexMap& vertices, int u, int v,
                             const NormalEstimationParams& p) {
  const Eigen::Vector3f centre = vertices(u, v);
  if (!is_valid(centre)) return invalid_vector();
  const float jump = p.max_depth_jump * centre.z();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int count = 0;
  for (int dv = -p.half_window; dv <= p.half_window; ++dv) {
    for (int du = -p.half_window; du <= p.half_window; ++du) {
      if (!vertices.in_bounds(u + du, v + dv)) continue;
      const Eigen::Vector3f& X = vertices(u + du, v + dv);
      if (!is_valid(X) || std::abs(X.z() - centre.z()) > jump) continue;
      const Eigen::Vector3d d = (X - centre).cast<double>();  // centred for precision
      sum += d;
      outer += d * d.transpose();
      ++count;
    }
  }
  if (count < p.min_points) return invalid_vector();
  const Eigen::Vector3d mean = sum / count;
  const Eigen::Matrix3d scatter = outer / count - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(scatter);
  const Eigen::Vector3d ev = eig.eigenvalues();
  // Collinear points (a line of pixels) leave the plane undetermined.
  if (!(ev(1) > 1e-6 * ev(2)) || !std::isfinite(ev(0))) return invalid_vector();
  Eigen::Vector3f n = eig.eigenvectors().col(0).cast<float>().normalized();
  if (n.dot(centre) > 0.0f) n = -n;  // toward the camera
  return n;
}

}  // namespace

void NormalEstimationParams::validate() const {
  if (half_window < 1 || half_window > 32) throw InputError("half_window: must be in [1, 32]");
  if (min_points < 3) throw InputError("min_points: must be at least 3");
  if (!(max_depth_jump > 0.0f))
    throw InputError("max_depth_jump: must be positive (fraction of depth)");
}

NormalMap estimate_normals(const VertexMap& vertices, const NormalEstimationParams& params) {
  NormalMap normals(vertices.width(), vertices.height(), invalid_vector());
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < vertices.height(); ++v)
    for (int u = 0; u < vertices.width(); ++u)
      normals(u, v) = plane_normal(vertices, u, v, params);
  return normals;
}

}  // namespace jpcr
