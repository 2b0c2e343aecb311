#include "jpcr/quadric/quadric_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <stdexcept>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/sample_columns.hpp"

namespace jpcr {

namespace {

// Quad IT at one pixel, the CPU way: the neighbourhood is gathered once into contiguous arrays
// (centred on p̄), then each Gauss-Newton iteration linearises all samples in one SIMD loop that
// writes √w (J, r) as columns, and the normal equations are their column products
// (sample_columns.hpp). Same math, parameters and stopping rule as fit_quadric_pixel
// (quadric_fit_kernel.hpp), which the CUDA kernel runs; tests compare the two.
class GatheredFit {
 public:
  GatheredFit(const NeighbourhoodPattern& pattern, int width)
      : capacity_((static_cast<int>(pattern.size()) + kLanes - 1) / kLanes * kLanes),
        buffer_(static_cast<std::size_t>(capacity_) * (kArrays + kQuadricColumns)) {
    for (const PixelOffset& o : pattern.offsets) {
      reach_ = std::max({reach_, std::abs(o.du), std::abs(o.dv)});
      linear_.push_back(static_cast<std::ptrdiff_t>(o.dv) * width + o.du);
    }
  }

  QuadricStatus run(const VertexMap& vertices, const NeighbourhoodPattern& pattern, int u, int v,
                    const Eigen::Vector3f& normal, const QuadricFitParams& p, Quadricd& out) {
    const Eigen::Vector3f& centre = vertices(u, v);
    if (!is_finite_value(centre.z())) return QuadricStatus::kNoCentre;
    if (!is_finite_value(normal.z())) return QuadricStatus::kNoNormal;
    const int n = gather(vertices, pattern, u, v, centre);
    if (n < p.min_samples) return QuadricStatus::kTooFewSamples;
    const GatheredSamples<float> samples{array(0), array(1), array(2),
                                         array(3), array(4), (n + kLanes - 1) / kLanes * kLanes};
    // The model in centred coordinates (p̄ = 0), so sample coordinates stay small in float.
    Quadricd q;
    q.R = local_frame<double>(normal.cast<double>().normalized());
    const SampleGate<double> limits = SampleGate<double>::at(p, centre.cast<double>());
    const float gate = static_cast<float>(limits.gate), n0 = static_cast<float>(limits.n0);
    Quadricd previous = q;
    double previous_cost = INFINITY;
    for (int it = 0; it <= p.iterations; ++it) {
      const QuadricScalars<float> qs = QuadricScalars<float>::from(q.cast<float>());
      if (it == p.iterations) {  // one pass more than steps: it checks the last one
        const SampleCosts c = sample_costs(qs, samples, gate, n0);
        if (c.inliers / std::max(1, c.count) > previous_cost) q = previous;
        break;
      }
      const SampleCosts c = fill_sample_columns<float, kQuadricColumns>(qs, samples, gate, n0,
                                                                        capacity_, array(kArrays));
      const double cost = c.inliers / std::max(1, c.count);  // mean Σ w r² over the inliers
      if (cost > previous_cost) {  // the last step made the fit worse: undo it and stop
        q = previous;
        break;
      }
      if (c.count < p.min_samples) return QuadricStatus::kTooFewSamples;
      double Y[100];
      column_products(array(kArrays), samples.n, capacity_, kQuadricColumns, Y);
      NormalEquations6<double> ne;  // Σ w J Jᵀ and Σ w J r (sample_columns.hpp)
      for (int i = 0; i < 6; ++i) {
        for (int j = 0; j < 6; ++j)
          ne.H(i, j) = kGammaSign[i] * kGammaSign[j] * Y[kGammaColumn[i] * 10 + kGammaColumn[j]];
        ne.g(i) = kGammaSign[i] * Y[kGammaColumn[i] * 10 + kColR];
      }
      previous = q;
      previous_cost = cost;
      Eigen::Matrix<double, 6, 1> delta;
      if (!solve_damped_step(ne, p.damping, delta)) return QuadricStatus::kSingular;
      apply_quadric_update(q, QuadricVector<double>(delta));
      if (step_converged(delta, p)) break;
    }
    q.center = centre.cast<double>();
    out = q;
    return QuadricStatus::kValid;
  }

 private:
  static constexpr int kArrays = 5;  // dx dy dz d² and the mask m (0 for padding), then columns
  static constexpr int kLanes = 8;   // samples per SIMD block

  float* array(int i) { return buffer_.data() + static_cast<std::size_t>(i) * capacity_; }

  // Gathers the valid samples as d = X − p̄; pads to a whole block with masked-out samples.
  int gather(const VertexMap& vertices, const NeighbourhoodPattern& pattern, int u, int v,
             const Eigen::Vector3f& centre) {
    float *dx = array(0), *dy = array(1), *dz = array(2), *d2 = array(3), *m = array(4);
    int n = 0;
    if (u >= reach_ && v >= reach_ && u + reach_ < vertices.width() &&
        v + reach_ < vertices.height()) {
      // The whole pattern is in the image: no bounds checks, and a branch-free compaction (each
      // sample is written, the count advances only past finite ones).
      const Eigen::Vector3f* row = &vertices(u, v);
      for (const std::ptrdiff_t offset : linear_) {
        const Eigen::Vector3f d = row[offset] - centre;
        dx[n] = d.x();
        dy[n] = d.y();
        dz[n] = d.z();
        n += is_finite_value(d.z()) ? 1 : 0;
      }
    } else {
      for (const PixelOffset& o : pattern.offsets) {
        const int su = u + o.du, sv = v + o.dv;
        if (!vertices.in_bounds(su, sv)) continue;  // 2-D bounds check (method.md §2)
        const Eigen::Vector3f d = vertices(su, sv) - centre;
        if (!is_finite_value(d.z())) continue;
        dx[n] = d.x();
        dy[n] = d.y();
        dz[n] = d.z();
        ++n;
      }
    }
    for (int k = 0; k < n; ++k) {
      d2[k] = dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k];
      m[k] = 1.0f;
    }
    for (int k = n; k % kLanes != 0; ++k)
      dx[k] = dy[k] = dz[k] = d2[k] = m[k] = 0.0f;
    return n;
  }

  int capacity_ = 0;
  std::vector<float> buffer_;
  int reach_ = 0;                       // max |du|, |dv| of the pattern
  std::vector<std::ptrdiff_t> linear_;  // dv · width + du per offset
};

}  // namespace

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
  QuadricMap map(vertices.width(), vertices.height());
#pragma omp parallel
  {
    GatheredFit fit(pattern, vertices.width());
#pragma omp for schedule(dynamic, 4)
    for (int v = 0; v < vertices.height(); ++v) {
      for (int u = 0; u < vertices.width(); ++u) {
        Quadricd q;
        const QuadricStatus status =
            fit.run(vertices, pattern, u, v, normals(u, v), params_.fit, q);
        if (status == QuadricStatus::kValid)
          map.set(u, v, q.cast<float>());
        else
          map.set_invalid(u, v, status);
      }
    }
  }
  return map;
}

}  // namespace jpcr
