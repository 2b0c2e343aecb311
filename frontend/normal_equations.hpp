// The reduction of ICP-ftf: Gauss-Newton normal equations H = Σ w JᵀJ and b = Σ w Jᵀ e summed
// over pixels (method.md §5). Only the 21 upper-triangle entries of H are accumulated, plus the
// 6 of b, the robust cost Σ w e² and the counts; per-thread sums are added at the end.
#pragma once

#include <cstddef>

#include <Eigen/Core>

#include "jpcr/quadric/se3.hpp"

namespace jpcr {

struct NormalEquations {
  double upper[21] = {};     // H row by row, upper triangle
  double b[6] = {};          // Σ w J e
  double cost = 0.0;         // Σ w e²
  double sum_squares = 0.0;  // Σ e² (unweighted, for the RMS)
  double sum_weights = 0.0;
  double normal_disagreement = 0.0;  // Σ w |R n_source − n_target|² over the pairs (0 if unset)
  double point_moments[9] = {};  // Σ w p (3), Σ w p pᵀ upper triangle (6) of the points J is at
  std::size_t inliers = 0;       // pairs that passed the rejection tests
  std::size_t valid = 0;         // source points considered
  std::size_t visible = 0;  // of those, projected onto a valid target vertex (before rejection)

  /// Adds w JᵀJ, w J e for one pair. J is single precision (the inner loop), sums are double.
  void add(const Eigen::Matrix<float, 6, 1>& J, float e, float w) {
    const double we = static_cast<double>(w) * e;
    int k = 0;
    for (int i = 0; i < 6; ++i) {
      const double wj = static_cast<double>(w) * J[i];
      for (int j = i; j < 6; ++j)
        upper[k++] += wj * J[j];
      b[i] += we * J[i];
    }
    cost += we * e;
    sum_squares += static_cast<double>(e) * e;
    sum_weights += w;
    ++inliers;
  }

  NormalEquations& operator+=(const NormalEquations& o) {
    for (int k = 0; k < 21; ++k)
      upper[k] += o.upper[k];
    for (int i = 0; i < 6; ++i)
      b[i] += o.b[i];
    cost += o.cost;
    sum_squares += o.sum_squares;
    sum_weights += o.sum_weights;
    normal_disagreement += o.normal_disagreement;
    for (int k = 0; k < 9; ++k)
      point_moments[k] += o.point_moments[k];
    inliers += o.inliers;
    valid += o.valid;
    visible += o.visible;
    return *this;
  }

  Matrix6d hessian() const {
    Matrix6d H;
    int k = 0;
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j)
        H(i, j) = H(j, i) = upper[k++];
    return H;
  }

  Vector6d gradient() const { return Eigen::Map<const Vector6d>(b); }
};

}  // namespace jpcr
