#include "jpcr/quadric/quadric_fit.hpp"

#include <cmath>
#include <stdexcept>

#include "jpcr/quadric/error.hpp"
#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

// Quad IT at one pixel, the CPU way: the neighbourhood is gathered once into contiguous arrays
// (centred on p̄), then each Gauss-Newton iteration evaluates linearize_sample on all samples in
// one SIMD loop that also accumulates the 27 numbers of the normal equations.
// Same math, parameters and stopping rule as fit_quadric_pixel (quadric_fit_kernel.hpp), which
// the CUDA kernel runs; tests compare the two.
class GatheredFit {
 public:
  explicit GatheredFit(int capacity)
      : buffer_(static_cast<std::size_t>((capacity + kLanes - 1) / kLanes * kLanes) * kArrays) {}

  JPCR_SIMD_CLONES QuadricStatus run(const VertexMap& vertices, const NeighbourhoodPattern& pattern,
                                     int u, int v, const Eigen::Vector3f& normal,
                                     const QuadricFitParams& p, Quadricd& out) {
    const Eigen::Vector3f& centre = vertices(u, v);
    if (!is_finite_value(centre.z())) return QuadricStatus::kNoCentre;
    if (!is_finite_value(normal.z())) return QuadricStatus::kNoNormal;
    const int n = gather(vertices, pattern, u, v, centre);
    if (n < p.min_samples) return QuadricStatus::kTooFewSamples;
    // The model in centred coordinates (p̄ = 0), so sample coordinates stay small in float.
    Quadricd q;
    q.R = local_frame<double>(normal.cast<double>().normalized());
    const SampleGate<double> limits = SampleGate<double>::at(p, centre.cast<double>());
    const float gate = static_cast<float>(limits.gate), n0 = static_cast<float>(limits.n0);
    Quadricd previous = q;
    double previous_cost = INFINITY;
    for (int it = 0; it <= p.iterations; ++it) {
      const QuadricScalars<float> qs = QuadricScalars<float>::from(q.cast<float>());
      const float *dx = array(0), *dy = array(1), *dz = array(2), *d2 = array(3), *m = array(4);
      // The 21 + 6 sums of the normal equations (lower triangle of Σ w JᵀJ, Σ w J r) and the
      // gated count, accumulated per SIMD lane over blocks of kLanes samples.
      float acc[29][kLanes] = {};
      for (int k0 = 0; k0 < n; k0 += kLanes) {
        for (int lane = 0; lane < kLanes; ++lane) {
          const int k = k0 + lane;
          const SampleLinearization<float> l = linearize_sample(qs, dx[k], dy[k], dz[k]);
          const float inside = m[k] * (std::abs(l.r) <= gate ? 1.0f : 0.0f);  // the gate
          const float w = inside * fair_weight(l.r, d2[k], n0);
          const float J[6] = {l.J0, l.J1, l.J2, l.J3, l.J4, l.J5};
          acc[0][lane] += w * J[0] * J[0];
          acc[1][lane] += w * J[1] * J[0];
          acc[2][lane] += w * J[1] * J[1];
          acc[3][lane] += w * J[2] * J[0];
          acc[4][lane] += w * J[2] * J[1];
          acc[5][lane] += w * J[2] * J[2];
          acc[6][lane] += w * J[3] * J[0];
          acc[7][lane] += w * J[3] * J[1];
          acc[8][lane] += w * J[3] * J[2];
          acc[9][lane] += w * J[3] * J[3];
          acc[10][lane] += w * J[4] * J[0];
          acc[11][lane] += w * J[4] * J[1];
          acc[12][lane] += w * J[4] * J[2];
          acc[13][lane] += w * J[4] * J[3];
          acc[14][lane] += w * J[4] * J[4];
          acc[15][lane] += w * J[5] * J[0];
          acc[16][lane] += w * J[5] * J[1];
          acc[17][lane] += w * J[5] * J[2];
          acc[18][lane] += w * J[5] * J[3];
          acc[19][lane] += w * J[5] * J[4];
          acc[20][lane] += w * J[5] * J[5];
          acc[21][lane] += w * J[0] * l.r;
          acc[22][lane] += w * J[1] * l.r;
          acc[23][lane] += w * J[2] * l.r;
          acc[24][lane] += w * J[3] * l.r;
          acc[25][lane] += w * J[4] * l.r;
          acc[26][lane] += w * J[5] * l.r;
          acc[27][lane] += inside;
          acc[28][lane] += w * l.r * l.r;
        }
      }
      NormalEquations6<double> ne;
      int sum = 0;
      auto total = [&](int row) {
        double t = 0.0;
        for (int lane = 0; lane < kLanes; ++lane)
          t += acc[row][lane];
        return t;
      };
      ne.H(0, 0) = total(0);
      ne.H(1, 0) = total(1);
      ne.H(1, 1) = total(2);
      ne.H(2, 0) = total(3);
      ne.H(2, 1) = total(4);
      ne.H(2, 2) = total(5);
      ne.H(3, 0) = total(6);
      ne.H(3, 1) = total(7);
      ne.H(3, 2) = total(8);
      ne.H(3, 3) = total(9);
      ne.H(4, 0) = total(10);
      ne.H(4, 1) = total(11);
      ne.H(4, 2) = total(12);
      ne.H(4, 3) = total(13);
      ne.H(4, 4) = total(14);
      ne.H(5, 0) = total(15);
      ne.H(5, 1) = total(16);
      ne.H(5, 2) = total(17);
      ne.H(5, 3) = total(18);
      ne.H(5, 4) = total(19);
      ne.H(5, 5) = total(20);
      ne.g(0) = total(21);
      ne.g(1) = total(22);
      ne.g(2) = total(23);
      ne.g(3) = total(24);
      ne.g(4) = total(25);
      ne.g(5) = total(26);
      sum = static_cast<int>(total(27));
      const double cost = total(28) / std::max(1, sum);
      if (cost > previous_cost) {  // the last step made the fit worse: undo it and stop
        q = previous;
        break;
      }
      if (it == p.iterations) break;  // one pass more than steps: it checks the last one
      if (sum < p.min_samples) return QuadricStatus::kTooFewSamples;
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
  static constexpr int kArrays = 5;  // dx dy dz d² and the mask m (0 for padding)
  static constexpr int kLanes = 8;   // samples per SIMD block

  float* array(int i) { return buffer_.data() + static_cast<std::size_t>(i) * capacity(); }
  std::size_t capacity() const { return buffer_.size() / kArrays; }

  // Gathers the valid samples as d = X − p̄; pads to a whole block with masked-out samples.
  int gather(const VertexMap& vertices, const NeighbourhoodPattern& pattern, int u, int v,
             const Eigen::Vector3f& centre) {
    float *dx = array(0), *dy = array(1), *dz = array(2), *d2 = array(3), *m = array(4);
    int n = 0;
    for (const PixelOffset& o : pattern.offsets) {
      const int su = u + o.du, sv = v + o.dv;
      if (!vertices.in_bounds(su, sv)) continue;  // 2-D bounds check (method.md §2)
      const Eigen::Vector3f& X = vertices(su, sv);
      if (!is_finite_value(X.z())) continue;
      const Eigen::Vector3f d = X - centre;
      dx[n] = d.x();
      dy[n] = d.y();
      dz[n] = d.z();
      d2[n] = d.squaredNorm();
      m[n] = 1.0f;
      ++n;
    }
    for (int k = n; k % kLanes != 0; ++k)
      dx[k] = dy[k] = dz[k] = d2[k] = m[k] = 0.0f;
    return n;
  }

  std::vector<float> buffer_;
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
    GatheredFit fit(pattern.size());
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
