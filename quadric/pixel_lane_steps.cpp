#include "jpcr/quadric/pixel_lane_steps.hpp"

#include <algorithm>
#include <cmath>

#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

constexpr int kLanes = kPixelLanes;

// H = L D Lᵀ per lane, column by column: D_j = H_jj − Σ_k L_jk (D_k L_jk), and for i > j
// D_j L_ij = H_ij − Σ_k L_ik (D_k L_jk), kept in the upper triangle (H[j][i]) while L_ij
// replaces H_ij in the lower one; then L y = −g and D Lᵀ Δ = y. No square roots, one division
// per pivot. The pivot test is cholesky_factor's (its L_jj² is D_j). As solve_damped_step, the
// system is solved in the range units of range_unit_scales, S[i][l] the scales of lane l.
JPCR_SIMD_CLONES void lane_steps(const PixelLaneSums& s, const double damping[kPixelLanes],
                                 const double range[kPixelLanes], double delta[6][kPixelLanes],
                                 bool ok[kPixelLanes]) {
  const auto tri = [](int a, int b) { return a >= b ? a * (a + 1) / 2 + b : b * (b + 1) / 2 + a; };
  double H[6][6][kLanes];  // lower: H, then L_ij; upper: D_j L_ij
  double inverse[6][kLanes], floor[kLanes];
  double S[6][kLanes];
  bool good[kLanes];
  for (int l = 0; l < kLanes; ++l) {
    double s_l[6];
    range_unit_scales(range[l], s_l);
    for (int i = 0; i < 6; ++i)
      S[i][l] = s_l[i];
  }
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j <= i; ++j) {
      const double sign = kGammaSign[i] * kGammaSign[j];
      const float* y = s.products[tri(kGammaColumn[i], kGammaColumn[j])];
#pragma omp simd
      for (int l = 0; l < kLanes; ++l)
        H[i][j][l] = S[i][l] * (sign * y[l]) * S[j][l];
    }
    const float* y = s.products[tri(kGammaColumn[i], kColR)];
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      delta[i][l] = -S[i][l] * (kGammaSign[i] * y[l]);
  }
  bool regular[kLanes];  // the undamped system's test, solve_damped_step's (kSingularPivot)
  for (int l = 0; l < kLanes; ++l) {
    Eigen::Matrix<double, 6, 6> lane;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j <= i; ++j)
        lane(i, j) = H[i][j][l];
    regular[l] = unit_diagonal_regular<double, 6>(lane, kSingularPivot);
  }
  for (int i = 0; i < 6; ++i)
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      H[i][i][l] *= 1.0 + damping[l];
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const double m01 = std::max(H[0][0][l], H[1][1][l]), m23 = std::max(H[2][2][l], H[3][3][l]);
    const double max_diag = std::max(std::max(m01, m23), std::max(H[4][4][l], H[5][5][l]));
    floor[l] = 1e-12 * max_diag;
    good[l] = max_diag > 0.0 && regular[l];  // false for NaN too
  }
  for (int j = 0; j < 6; ++j) {
    for (int i = j; i < 6; ++i)  // column j: D_j (i = j), then D_j L_ij
      for (int k = 0; k < j; ++k)
#pragma omp simd
        for (int l = 0; l < kLanes; ++l)
          H[i][j][l] -= H[i][k][l] * H[k][j][l];
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      good[l] = good[l] && H[j][j][l] > floor[l];  // also catches NaN
      inverse[j][l] = 1.0 / H[j][j][l];
    }
    for (int i = j + 1; i < 6; ++i) {
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) {
        H[j][i][l] = H[i][j][l];
        H[i][j][l] *= inverse[j][l];
      }
    }
  }
  for (int i = 0; i < 6; ++i)  // L y = −g
    for (int k = 0; k < i; ++k)
#pragma omp simd
      for (int l = 0; l < kLanes; ++l)
        delta[i][l] -= H[i][k][l] * delta[k][l];
  for (int i = 5; i >= 0; --i) {  // D Lᵀ Δ = y
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      delta[i][l] *= inverse[i][l];
    for (int k = i + 1; k < 6; ++k)
#pragma omp simd
      for (int l = 0; l < kLanes; ++l)
        delta[i][l] -= H[k][i][l] * delta[k][l];
  }
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    bool finite = good[l];
    for (int i = 0; i < 6; ++i) {
      delta[i][l] *= S[i][l];
      finite = finite && delta[i][l] - delta[i][l] == 0.0;
    }
    ok[l] = finite;
  }
}

// (−1)ⁿ / (2n + offset)!: the coefficient of θ²ⁿ in sin θ / θ (offset 1) and in
// (1 − cos θ) / θ² (offset 2).
constexpr double series_term(int n, int offset) {
  double factorial = 1.0;
  for (int i = 2; i <= 2 * n + offset; ++i)
    factorial *= i;
  return (n % 2 == 0 ? 1.0 : -1.0) / factorial;
}
constexpr int kSeriesTerms = 9;  // up to θ¹⁶

struct Series {
  double sinc[kSeriesTerms], cosc[kSeriesTerms];
};
constexpr Series kSeries = [] {
  Series c{};
  for (int n = 0; n < kSeriesTerms; ++n) {
    c.sinc[n] = series_term(n, 1);
    c.cosc[n] = series_term(n, 2);
  }
  return c;
}();

// Rodrigues per lane (apply_quadric_update): with θ² = Δω₁² + Δω₂², s = sin θ / θ and
// k = (1 − cos θ) / θ², exp([ω]×) = I + s W + k W² is
//   [[1 − k ω₂², k ω₁ ω₂, s ω₂], [k ω₁ ω₂, 1 − k ω₁², −s ω₁], [−s ω₂, s ω₁, 1 − k θ²]].
// s and k from their Taylor series in θ² up to θ¹⁶ (the next term is below 1e-19 for θ ≤ 0.5).
JPCR_SIMD_CLONES void lane_updates(LaneQuadrics& q, const double delta[6][kLanes],
                                   const bool take[kLanes], const QuadricFitParams& p,
                                   bool converged[kLanes]) {
  double s[kLanes], k[kLanes];
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const double t = delta[0][l] * delta[0][l] + delta[1][l] * delta[1][l];
    double sl = kSeries.sinc[kSeriesTerms - 1], kl = kSeries.cosc[kSeriesTerms - 1];
    for (int n = kSeriesTerms - 2; n >= 0; --n) {  // Horner in θ²
      sl = sl * t + kSeries.sinc[n];
      kl = kl * t + kSeries.cosc[n];
    }
    s[l] = sl;
    k[l] = kl;
  }
  for (int l = 0; l < kLanes; ++l) {  // beyond the series' range (rare): the functions themselves
    const double t = delta[0][l] * delta[0][l] + delta[1][l] * delta[1][l];
    if (take[l] && t > 0.25) {
      const double theta = std::sqrt(t);
      s[l] = std::sin(theta) / theta;
      k[l] = (1.0 - std::cos(theta)) / t;
    }
  }
  double(*R)[kLanes] = q.row;
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const double w1 = delta[0][l], w2 = delta[1][l], sl = s[l], kl = k[l];
    // clang-format off
    const double e[9] = {1.0 - kl * w2 * w2, kl * w1 * w2,       sl * w2,
                         kl * w1 * w2,       1.0 - kl * w1 * w1, -sl * w1,
                         -sl * w2,           sl * w1,            1.0 - kl * (w1 * w1 + w2 * w2)};
    // clang-format on
    double next[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        next[3 * i + j] =
            e[3 * i] * R[j][l] + e[3 * i + 1] * R[3 + j][l] + e[3 * i + 2] * R[6 + j][l];
    for (int i = 0; i < 9; ++i)
      R[i][l] = take[l] ? next[i] : R[i][l];
    for (int i = 2; i < 6; ++i)  // t_z, a, b, c
      q.row[LaneQuadrics::kTz + i - 2][l] += take[l] ? delta[i][l] : 0.0;
    const double dw = w1 * w1 + w2 * w2;
    const double dk =
        std::max(std::abs(delta[3][l]), std::max(std::abs(delta[4][l]), std::abs(delta[5][l])));
    converged[l] = dw < double(p.angle_tolerance) * p.angle_tolerance &&
                   std::abs(delta[2][l]) < p.offset_tolerance && dk < p.curvature_tolerance;
  }
}

}  // namespace

void pixel_lane_steps(const PixelLaneSums& sums, const double damping[kPixelLanes],
                      const double range[kPixelLanes], double delta[6][kPixelLanes],
                      bool ok[kPixelLanes]) {
  lane_steps(sums, damping, range, delta, ok);
}

void pixel_lane_updates(LaneQuadrics& q, const double delta[6][kPixelLanes],
                        const bool take[kPixelLanes], const QuadricFitParams& p,
                        bool converged[kPixelLanes]) {
  lane_updates(q, delta, take, p, converged);
}

}  // namespace jpcr
