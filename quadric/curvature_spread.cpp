#include "jpcr/quadric/curvature_spread.hpp"

#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/parallel_guard.hpp"
#include "jpcr/quadric/sample_columns.hpp"

namespace jpcr {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The header's sums at one pixel in float lanes (sample_columns.hpp): the samples are gathered
// centred on p̄, fill_sample_columns writes √w (y, r) for the samples inside the gate with the
// fit's own gate and Fair weight (accumulate_quadric_samples' rules), and the product columns
// (√w r)(√w y) = w r y give M = Σ w² r² y yᵀ as H = Σ w y yᵀ is given, by column_products.
class SpreadSums {
 public:
  static constexpr int kLanes = 8;                   // one AVX register of floats
  static constexpr int kProducts = kQuadricColumns;  // first of the 6 product columns

  explicit SpreadSums(int pattern_size)
      : capacity_((pattern_size + kLanes - 1) / kLanes * kLanes),
        samples_(static_cast<std::size_t>(capacity_) * 5),
        columns_(static_cast<std::size_t>(capacity_) * (kQuadricColumns + 6)) {}

  // H and M in γ order (ω₁, ω₂, t_z, a, b, c) and the count inside the gate.
  int sums(const Quadricd& q, const VertexView& view, const NeighbourhoodPattern& pattern,
           const QuadricFitParams& fit, int u, int v, Matrix6d& H, Matrix6d& M, int& samples) {
    float *dx = sample(0), *dy = sample(1), *dz = sample(2), *d2 = sample(3), *mask = sample(4);
    int n = 0;
    for (const PixelOffset& o : pattern.offsets) {
      const int su = u + o.du, sv = v + o.dv;
      if (!view.in_bounds(su, sv) || !is_sample_point(view(su, sv))) continue;
      const Eigen::Vector3d d = view(su, sv).cast<double>() - q.center;  // centred in double
      dx[n] = static_cast<float>(d.x());
      dy[n] = static_cast<float>(d.y());
      dz[n] = static_cast<float>(d.z());
      d2[n] = static_cast<float>(d.squaredNorm());
      mask[n] = 1.0f;
      ++n;
    }
    samples = n;
    for (; n % kLanes != 0; ++n)
      dx[n] = dy[n] = dz[n] = d2[n] = mask[n] = 0.0f;
    const SampleGate<double> limits = SampleGate<double>::at(fit, q.center);
    const GatheredSamples<float> s{dx, dy, dz, d2, mask, n};
    const SampleCosts costs = fill_sample_columns<float, kQuadricColumns>(
        QuadricScalars<float>::from(q.cast<float>()), s, static_cast<float>(limits.gate),
        static_cast<float>(limits.n0), capacity_, column(0));
    const float* r = column(kColR);
    for (int c = 0; c < 6; ++c) {
      const float* y = column(c);
      float* product = column(kProducts + c);
      for (int k = 0; k < n; ++k)
        product[k] = y[k] * r[k];
    }
    double Yh[100], Ym[100];
    column_products<float>(column(0), n, capacity_, 6, Yh);
    column_products<float>(column(kProducts), n, capacity_, 6, Ym);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) {
        const int a = kGammaColumn[i] * 10 + kGammaColumn[j];
        const double sign = kGammaSign[i] * kGammaSign[j];
        H(i, j) = sign * Yh[a];
        M(i, j) = sign * Ym[a];
      }
    return costs.count;
  }

 private:
  float* sample(int i) { return samples_.data() + static_cast<std::size_t>(i) * capacity_; }
  float* column(int i) { return columns_.data() + static_cast<std::size_t>(i) * capacity_; }

  int capacity_;
  std::vector<float> samples_;  // dx dy dz d² mask
  std::vector<float> columns_;  // √w (y, r), then w r y
};

// Cov(γ) = n / (n − 6) · H⁻¹ M H⁻¹ and sd from its (a, b, c) block (header).
double spread_at(const Quadricd& q, const VertexView& view, const NeighbourhoodPattern& pattern,
                 const QuadricFitParams& fit, int u, int v, SpreadSums& sums) {
  Matrix6d H, M;
  int samples = 0;
  const int n = sums.sums(q, view, pattern, fit, u, v, H, M, samples);
  if (n < fit.min_samples || n <= 6) return kNaN;
  if (n < kMinInsideFraction * samples) return kNaN;
  // In the range units of Quad IT's solve (range_unit_scales), where a scaled scene gives the same
  // system, so the singularity floor means the same at every range.
  double s[6];
  range_unit_scales(q.center.norm(), s);
  const Eigen::DiagonalMatrix<double, 6> S(Vector6d(s[0], s[1], s[2], s[3], s[4], s[5]));
  const Matrix6d Hs = S * H * S;
  if (!unit_diagonal_regular<double, 6>(Hs, kSingularPivot)) return kNaN;
  const Eigen::LLT<Matrix6d> llt(Hs);
  if (llt.info() != Eigen::Success) return kNaN;
  const Matrix6d A = llt.solve(Matrix6d::Identity());  // Hs⁻¹
  const Matrix6d cov = S * (A * (S * M * S) * A) * S * (double(n) / double(n - 6));
  // γ = (ω₁, ω₂, t_z, a, b, c): ‖δK‖²_F = δa² + 2 δb² + δc².
  const double frobenius2 = cov(3, 3) + 2.0 * cov(4, 4) + cov(5, 5);
  return frobenius2 >= 0.0 ? std::sqrt(0.5 * frobenius2) : kNaN;
}

void check_sizes(const QuadricMap& map, const VertexMap& vertices) {
  if (map.width() != vertices.width() || map.height() != vertices.height())
    throw InputError("curvature_spread: the map is " + std::to_string(map.width()) + "x" +
                     std::to_string(map.height()) + " but the vertices are " +
                     std::to_string(vertices.width()) + "x" + std::to_string(vertices.height()));
}

}  // namespace

double curvature_spread_at(const QuadricMap& map, const VertexMap& vertices,
                           const NeighbourhoodPattern& pattern, const QuadricFitParams& fit, int u,
                           int v) {
  check_sizes(map, vertices);
  if (!map.status.in_bounds(u, v) || !map.valid(u, v)) return kNaN;
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  SpreadSums sums(pattern.size());
  return spread_at(map.quadrics(u, v).cast<double>(), view, pattern, fit, u, v, sums);
}

Image<float> curvature_spread(const QuadricMap& map, const VertexMap& vertices,
                              const NeighbourhoodPattern& pattern, const QuadricFitParams& fit) {
  check_sizes(map, vertices);
  Image<float> sd(map.width(), map.height(), std::numeric_limits<float>::quiet_NaN());
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  ParallelGuard guard;  // e.g. a worker's buffers out of memory: rethrown, not std::terminate
#pragma omp parallel
  {
    std::optional<SpreadSums> sums;
    guard.run([&] { sums.emplace(pattern.size()); });
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < map.height(); ++v)
      guard.run([&] {
        for (int u = 0; u < map.width() && sums; ++u)
          if (map.valid(u, v))
            sd(u, v) = static_cast<float>(
                spread_at(map.quadrics(u, v).cast<double>(), view, pattern, fit, u, v, *sums));
      });
  }
  guard.rethrow();
  return sd;
}

}  // namespace jpcr
