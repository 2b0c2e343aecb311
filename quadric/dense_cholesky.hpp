// A small dense Cholesky solve for the N×N normal equations of one quadric or one pose
// (N = 6 in Quad IT and J-ftf). Plain loops, no allocation, JPCR_HD: the CPU reference and the
// CUDA kernels solve the same way. Only the lower triangle of H is read.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "jpcr/quadric/host_device.hpp"

namespace jpcr {

/// Factorises H = L Lᵀ in place (lower triangle of L in the lower triangle of H). Returns false
/// when H is not numerically positive definite: a pivot ≤ eps_rel · max diagonal, or NaN.
template <typename Scalar, int N>
JPCR_HD bool cholesky_factor(Eigen::Matrix<Scalar, N, N>& H, Scalar eps_rel = Scalar(1e-12)) {
  Scalar max_diag = 0;
  for (int i = 0; i < N; ++i)
    max_diag = H(i, i) > max_diag ? H(i, i) : max_diag;
  if (!(max_diag > Scalar(0))) return false;
  const Scalar floor = eps_rel * max_diag;
  for (int j = 0; j < N; ++j) {
    Scalar d = H(j, j);
    for (int k = 0; k < j; ++k)
      d -= H(j, k) * H(j, k);
    if (!(d > floor)) return false;                          // also catches NaN
    const Scalar l = std::sqrt(d), inverse = Scalar(1) / l;  // one division per column
    H(j, j) = l;
    for (int i = j + 1; i < N; ++i) {
      Scalar s = H(i, j);
      for (int k = 0; k < j; ++k)
        s -= H(i, k) * H(j, k);
      H(i, j) = s * inverse;
    }
  }
  return true;
}

/// Whether the positive semi-definite H (lower triangle read) is numerically regular: every
/// pivot of its unit-diagonal form D^-½ H D^-½ (D = diag H; a correlation matrix, whose pivots
/// lie in (0, 1] and are at least its smallest eigenvalue) exceeds `floor`. Invariant to the
/// columns' scales, and it sees two columns equal up to scale, which a floor relative to the
/// largest diagonal misses and a Levenberg-Marquardt damping λ diag H would make solvable.
template <typename Scalar, int N>
JPCR_HD bool unit_diagonal_regular(const Eigen::Matrix<Scalar, N, N>& H, Scalar floor) {
  Scalar inverse_sqrt[N];
  for (int i = 0; i < N; ++i) {
    if (!(H(i, i) > Scalar(0))) return false;  // also NaN
    inverse_sqrt[i] = Scalar(1) / std::sqrt(H(i, i));
  }
  Eigen::Matrix<Scalar, N, N> C;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j <= i; ++j)
      C(i, j) = H(i, j) * inverse_sqrt[i] * inverse_sqrt[j];
  return cholesky_factor<Scalar, N>(C, floor);  // its floor is relative to the diagonal, 1 here
}

/// Solves L Lᵀ x = b with a factor from cholesky_factor, in place in b.
template <typename Scalar, int N>
JPCR_HD void cholesky_solve(const Eigen::Matrix<Scalar, N, N>& L, Eigen::Matrix<Scalar, N, 1>& b) {
  Scalar inverse[N];  // 1 / L_ii, one division per row for both substitutions
  for (int i = 0; i < N; ++i)
    inverse[i] = Scalar(1) / L(i, i);
  for (int i = 0; i < N; ++i) {
    Scalar s = b(i);
    for (int k = 0; k < i; ++k)
      s -= L(i, k) * b(k);
    b(i) = s * inverse[i];
  }
  for (int i = N - 1; i >= 0; --i) {
    Scalar s = b(i);
    for (int k = i + 1; k < N; ++k)
      s -= L(k, i) * b(k);
    b(i) = s * inverse[i];
  }
}

/// Solves L Lᵀ X = B for the C columns of B, in place: cholesky_solve on each column with the
/// same operations in the same order (the same result to the bit), the reciprocals of the
/// diagonal computed once for all columns.
template <typename Scalar, int N, int C>
JPCR_HD void cholesky_solve_columns(const Eigen::Matrix<Scalar, N, N>& L,
                                    Eigen::Matrix<Scalar, N, C>& B) {
  Scalar inverse[N];
  for (int i = 0; i < N; ++i)
    inverse[i] = Scalar(1) / L(i, i);
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < C; ++c) {
      Scalar s = B(i, c);
      for (int k = 0; k < i; ++k)
        s -= L(i, k) * B(k, c);
      B(i, c) = s * inverse[i];
    }
  for (int i = N - 1; i >= 0; --i)
    for (int c = 0; c < C; ++c) {
      Scalar s = B(i, c);
      for (int k = i + 1; k < N; ++k)
        s -= L(k, i) * B(k, c);
      B(i, c) = s * inverse[i];
    }
}

/// Copies the lower triangle of a symmetric matrix into its upper triangle.
template <typename Scalar, int N>
JPCR_HD void symmetrize_from_lower(Eigen::Matrix<Scalar, N, N>& H) {
  for (int i = 0; i < N; ++i)
    for (int j = i + 1; j < N; ++j)
      H(i, j) = H(j, i);
}

}  // namespace jpcr
