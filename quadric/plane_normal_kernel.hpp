// The initial normal of one pixel (method.md §3): a least-squares plane through the valid
// vertices of its (2h+1)x(2h+1) window, oriented toward the camera; where the window's points
// are evidently no single smooth surface (a depth step below the depth jump, a crease), the plane
// of the best of its four quadrants (choose_quadrant). JPCR_HD and allocation-free, so
// estimate_normals (surface_normals.cpp) and the CUDA Quad IT (cuda/) run exactly this code.
#pragma once

#include <limits>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "jpcr/quadric/quadric_fit_kernel.hpp"
#include "jpcr/quadric/surface_normals.hpp"

namespace jpcr {

/// The eigenvalues of a symmetric 3x3 S, ascending, in closed form (with q = tr S / 3,
/// p² = |S − q I|²_F / 6 and r = det((S − q I) / p) / 2, φ = acos(r) / 3: λ_max = q + 2p cos φ,
/// λ_min = q + 2p cos(φ + 2π/3), λ_mid = 3q − λ_min − λ_max); false where S is a multiple of I.
JPCR_HD bool closed_form_eigenvalues(const Eigen::Matrix3d& S, Eigen::Vector3d& eigenvalues) {
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
  return true;
}

/// The eigenvector of the smallest eigenvalue of a symmetric 3x3 S and its eigenvalues,
/// ascending: the eigenvalues in closed form (closed_form_eigenvalues), the eigenvector as the
/// longest cross product of two rows of S − λ_min I, the other two eigenvectors being in their
/// span. The method of Eigen's computeDirect for the one eigenvector a plane fit needs. False
/// where S is a multiple of I or the cross products are at rounding level; at a double smallest
/// eigenvalue (which this closed form splits by about √ε) the answer is some unit vector of that
/// eigenvalue's plane.
JPCR_HD bool smallest_eigenvector(const Eigen::Matrix3d& S, Eigen::Vector3d& n,
                                  Eigen::Vector3d& eigenvalues) {
  if (!closed_form_eigenvalues(S, eigenvalues)) return false;
  Eigen::Matrix3d B = S;
  B.diagonal().array() -= eigenvalues(0);  // S − λ_min I
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
/// count < p.min_points or the points are collinear. `residual`, where given, receives that
/// smallest eigenvalue: the mean squared distance of the points from their plane (m²).
JPCR_HD Eigen::Vector3f plane_normal_from_moments(const Eigen::Vector3d& sum,
                                                  const Eigen::Matrix3d& outer, int count,
                                                  const Eigen::Vector3f& centre,
                                                  const NormalEstimationParams& p,
                                                  double* residual = nullptr) {
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
  if (residual) *residual = ev(0) > 0.0 ? ev(0) : 0.0;
  return n;
}

/// Σ d, Σ d dᵀ and the count of the valid vertices X of the pixels (u + du, v + dv), du in
/// [u0, u1], dv in [v0, v1], within the depth jump of the centre's, with d = X − centre.
JPCR_HD void rectangle_moments(const VertexView& vertices, int u, int v, int u0, int u1, int v0,
                               int v1, const NormalEstimationParams& p, Eigen::Vector3d& sum,
                               Eigen::Matrix3d& outer, int& count) {
  sum.setZero();
  outer.setZero();
  count = 0;
  const Eigen::Vector3f centre = vertices(u, v);
  const float jump = p.max_depth_jump * centre.z();
  for (int dv = v0; dv <= v1; ++dv) {
    for (int du = u0; du <= u1; ++du) {
      if (!vertices.in_bounds(u + du, v + dv)) continue;
      const Eigen::Vector3f& X = vertices(u + du, v + dv);
      if (!is_sample_point(X) || fabsf(X.z() - centre.z()) > jump) continue;
      const Eigen::Vector3d d = (X - centre).cast<double>();
      sum += d;
      outer += d * d.transpose();
      ++count;
    }
  }
}

/// Σ d, Σ d dᵀ and the count of each of the four quadrants of a window that share its centre
/// pixel, (h+1)x(h+1) pixels each: [0] up-left, [1] up-right, [2] down-left, [3] down-right.
struct QuadrantMoments {
  Eigen::Vector3d sum[4];
  Eigen::Matrix3d outer[4];
  int count[4];
};

/// The quadrants' moments at (u, v), point by point (rectangle_moments).
JPCR_HD void quadrant_moments(const VertexView& vertices, int u, int v,
                              const NormalEstimationParams& p, QuadrantMoments& m) {
  const int h = p.half_window;
  for (int q = 0; q < 4; ++q) {
    const int u0 = (q & 1) ? 0 : -h, v0 = (q & 2) ? 0 : -h;
    rectangle_moments(vertices, u, v, u0, u0 + h, v0, v0 + h, p, m.sum[q], m.outer[q], m.count[q]);
  }
}

/// The normal given the window's plane (n, residual) and its quadrants' moments: the window's,
/// unless a quadrant fits a plane with a residual p.quadrant_ratio times smaller, whose normal it
/// then is (the smallest residual's). A straight step or crease near the centre leaves at least
/// one quadrant wholly on the centre's side. The window's plane tilted by 59–86° across such a
/// step, and Quad IT, which starts from it, did not recover: a band of about 6 pixels along it
/// came back valid with |κ| around 20 1/m on flat surfaces.
///
/// The ratio (default 100): on a smooth surface the residual is that of its quadric, which grows
/// with the fourth power of the patch's extent, so a quadrant (half the extent each way) has 1/16
/// of the window's (1/12 over the 7x7 pixel grid for a paraboloid, cylinder or saddle). Near a
/// silhouette the depth over the image is no quadric: on a sphere of radius 5 cm at 0.5 m the
/// ratio reached 46 (SurfaceNormals.ASmoothSurfaceKeepsTheWindowsPlane), and the quadrant's plane
/// was the worse there. Above 100 (RMS distances 10 times apart) the window's points are no
/// single smooth surface; without noise such a quadrant is an exact plane. Under range noise
/// every fit's residual is the noise's, and only a step of about 40 noise σ reaches the ratio.
JPCR_HD Eigen::Vector3f choose_quadrant(const QuadrantMoments& m, const Eigen::Vector3f& centre,
                                        const NormalEstimationParams& p, const Eigen::Vector3f& n,
                                        double residual) {
  int best = -1;
  double below = residual / p.quadrant_ratio;
  for (int q = 0; q < 4; ++q) {
    if (m.count[q] < p.min_points) continue;
    const Eigen::Vector3d mean = m.sum[q] / m.count[q];
    const Eigen::Matrix3d scatter = m.outer[q] / m.count[q] - mean * mean.transpose();
    // λ_min ≥ below exactly when scatter − below·I is positive semi-definite; Sylvester's
    // leading minors tell most quadrants (those of a smooth surface) without the eigenvalues.
    Eigen::Matrix3d A = scatter;
    A.diagonal().array() -= below;
    const double minor2 = A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1);
    if (A(0, 0) > 0.0 && minor2 > 0.0 && A.determinant() > 0.0) continue;
    Eigen::Vector3d ev;
    if (!closed_form_eigenvalues(scatter, ev)) continue;
    if (ev(0) < below) {
      best = q;
      below = ev(0);
    }
  }
  if (best < 0) return n;
  const Eigen::Vector3f nq =
      plane_normal_from_moments(m.sum[best], m.outer[best], m.count[best], centre, p);
  return nq.x() == nq.x() ? nq : n;  // a line of points has no plane: keep the window's
}

/// Whether the window's plane (n, residual) is one a quadrant could replace: a plane that is not
/// exact, and the choice not switched off.
JPCR_HD bool may_take_a_quadrant(const Eigen::Vector3f& n, double residual,
                                 const NormalEstimationParams& p) {
  return n.x() == n.x() && residual > 0.0 && p.quadrant_ratio > 0.0f;
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
  if (!is_sample_point(vertices(u, v))) return false;
  const int h = p.half_window;
  rectangle_moments(vertices, u, v, -h, h, -h, h, p, sum, outer, count);
  return true;
}

/// The plane normal at (u, v): the eigenvector of the smallest eigenvalue of the scatter matrix
/// of the window points about their mean (closed-form 3x3 solve, computeDirect, in double), or
/// a quadrant's where the window holds no single smooth surface (choose_quadrant). Unit,
/// n·X < 0; all-NaN where the centre has no vertex, too few window points remain or the points
/// are collinear. `window_normal`, where given, receives the window's own plane normal (the
/// result unless a quadrant replaced it; NaN where there is none).
JPCR_HD Eigen::Vector3f plane_normal(const VertexView& vertices, int u, int v,
                                     const NormalEstimationParams& p,
                                     Eigen::Vector3f* window_normal = nullptr) {
  Eigen::Vector3d sum;
  Eigen::Matrix3d outer;
  int count;
  const Eigen::Vector3f none = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  if (window_normal) *window_normal = none;
  if (!window_moments(vertices, u, v, p, sum, outer, count)) return none;
  double residual = 0.0;
  const Eigen::Vector3f n =
      plane_normal_from_moments(sum, outer, count, vertices(u, v), p, &residual);
  if (window_normal) *window_normal = n;
  if (!may_take_a_quadrant(n, residual, p)) return n;
  QuadrantMoments m;
  quadrant_moments(vertices, u, v, p, m);
  return choose_quadrant(m, vertices(u, v), p, n, residual);
}

}  // namespace jpcr
