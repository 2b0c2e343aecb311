// Quad IT for one pixel (method.md §3): the weighted Gauss-Newton fit of the quadric γ_p to the
// vertices of p's neighbourhood. JPCR_HD and allocation-free: the CUDA kernel (cuda/) runs
// exactly this code per pixel, and the dense CPU fit (quadric_fit.cpp) the same math with 16
// pixels in SIMD lanes (pixel_lane_sums.hpp, pixel_lane_steps.hpp); tests compare the two.
#pragma once

#include <cstddef>

#include <Eigen/Core>

#include "jpcr/quadric/dense_cholesky.hpp"
#include "jpcr/quadric/neighbourhood_pattern.hpp"
#include "jpcr/quadric/quadric_model.hpp"

namespace jpcr {

/// Quad IT tunables (method.md §3). A plain struct with the reference values; YAML maps onto it
/// in io/ (section `quadric:`), and the CUDA kernels receive it by value.
struct QuadricFitParams {
  int iterations = 3;            // Gauss-Newton iterations (the reference ran exactly 3)
  float fair_n0 = 0.004f;        // m: n₀ of the weight w = n₀² / (n₀² + r² + d²)
  float residual_gate = 0.014f;  // m: samples with |r| above it are dropped (depth edges)
  // The paper picks n "close to the upper limit of a typical error value"; for sensors whose noise
  // grows with range (the paper's k % protocol, Kinect) both constants can grow with it:
  // n₀(p) = fair_n0 + fair_n0_per_range · |p̄|, gate(p) = residual_gate + gate_per_range · |p̄|.
  float fair_n0_per_range = 0.0f;     // m per m of range (0: the reference constant n₀)
  float gate_per_range = 0.0f;        // m per m of range (0: the reference constant gate)
  float damping = 0.01f;              // relative Levenberg damping on the diagonal
  int min_samples = 10;               // fewer valid samples → the pixel is invalid
  float angle_tolerance = 1e-5f;      // rad: early stop when |Δω| ∞-norm is below it ...
  float offset_tolerance = 1e-6f;     // m:   ... and |Δt_z| below this ...
  float curvature_tolerance = 1e-3f;  // 1/m: ... and |Δ(a, b, c)| ∞-norm below this

  void validate() const;  // throws InputError "field: problem"
};

/// Why a pixel has no quadric.
enum class QuadricStatus : unsigned char {
  kValid = 0,
  kNoCentre,       // the centre pixel has no depth
  kNoNormal,       // no initial normal (too few neighbours for the plane fit)
  kTooFewSamples,  // fewer than min_samples samples passed the gate
  kSingular,       // the 6x6 system is singular or not finite
  kNoStep,         // no step from the starting plane lowered the cost: the plane is no fit
};

/// A read-only view of a vertex map that device code can hold (row-major, NaN = invalid).
struct VertexView {
  const Eigen::Vector3f* data = nullptr;
  int width = 0;
  int height = 0;

  JPCR_HD bool in_bounds(int u, int v) const { return u >= 0 && v >= 0 && u < width && v < height; }
  JPCR_HD const Eigen::Vector3f& operator()(int u, int v) const {
    return data[static_cast<std::ptrdiff_t>(v) * width + u];
  }
};

/// True for a finite float (false for NaN and ±Inf) without <cmath>'s host-only overloads.
JPCR_HD bool is_finite_value(float x) {
  return x - x == 0.0f;
}

/// The largest coordinate (m) of a vertex taken as a sample: beyond it the CPU fits' float sums
/// (fourth powers over a pattern, 129 · (1e7)⁴ ≈ 1e30 here) near overflow, while the double
/// reference kernels weigh the vertex to nothing, so the two would disagree. compute_vertex_map
/// keeps depth within kMaxMeasurableDepth (1e4 m): |x| stays below 9.2e5 m for any camera that
/// CameraIntrinsics::validate accepts; a caller's own map may hold a "no return" 1e25.
constexpr float kMaxSampleCoordinate = 1e7f;

/// True for a vertex that is a sample: its three coordinates finite and within
/// ±kMaxSampleCoordinate (vertex maps mark a pixel without depth with NaN, and a caller's map
/// may hold NaN in x or y alone). The one test of every fit (Quad IT, Quad LS), normal and joint
/// term, CPU and GPU.
JPCR_HD bool is_sample_point(const Eigen::Vector3f& X) {
  // false for NaN too
  return fabsf(X.x()) <= kMaxSampleCoordinate && fabsf(X.y()) <= kMaxSampleCoordinate &&
         fabsf(X.z()) <= kMaxSampleCoordinate;
}

/// Σ w JᵀJ (lower triangle) and Σ w J r of one 6-parameter problem over the samples inside the
/// gate (count of them), and the gated cost Σ w(e) e² over every sample with
/// depth, e = r inside the gate and e = ±gate outside (pixel_lane_sums' `gated`): a robust cost
/// over a set of samples that no step changes, which Quad IT's step test compares.
template <typename Scalar>
struct NormalEquations6 {
  Eigen::Matrix<Scalar, 6, 6> H = Eigen::Matrix<Scalar, 6, 6>::Zero();
  Eigen::Matrix<Scalar, 6, 1> g = Eigen::Matrix<Scalar, 6, 1>::Zero();
  Scalar gated = 0;
  int count = 0;

  JPCR_HD void add(const Eigen::Matrix<Scalar, 6, 1>& J, Scalar r, Scalar w) {
    for (int i = 0; i < 6; ++i) {
      const Scalar wJi = w * J(i);
      for (int j = 0; j <= i; ++j)
        H(i, j) += wJi * J(j);
      g(i) += wJi * r;
    }
    gated += w * r * r;
    ++count;
  }
  /// A sample outside the gate: w(gate) gate² to the gated cost only.
  JPCR_HD void add_outside(Scalar w_at_gate, Scalar gate) { gated += w_at_gate * gate * gate; }
};

/// The weight constant n₀ and the residual gate at a quadric centre p̄ (m).
template <typename Scalar>
struct SampleGate {
  Scalar n0;
  Scalar gate;

  JPCR_HD static SampleGate at(const QuadricFitParams& p,
                               const Eigen::Matrix<Scalar, 3, 1>& centre) {
    const Scalar range = centre.norm();
    return {Scalar(p.fair_n0) + Scalar(p.fair_n0_per_range) * range,
            Scalar(p.residual_gate) + Scalar(p.gate_per_range) * range};
  }
};

/// Adds the samples of `pattern` around (u, v) to the quadric normal equations (frame-1 terms of
/// method.md §3/§6): gate |r| ≤ gate, weight fair_weight(r, |X − p̄|², n₀).
template <typename Scalar>
JPCR_HD void accumulate_quadric_samples(const QuadricT<Scalar>& q, const VertexView& vertices,
                                        const PixelOffset* pattern, int pattern_size, int u, int v,
                                        const QuadricFitParams& p, NormalEquations6<Scalar>& ne) {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  const SampleGate<Scalar> limits = SampleGate<Scalar>::at(p, q.center);
  for (int k = 0; k < pattern_size; ++k) {
    const int su = u + pattern[k].du, sv = v + pattern[k].dv;
    if (!vertices.in_bounds(su, sv)) continue;  // 2-D bounds check (method.md §2)
    const Eigen::Vector3f& Xf = vertices(su, sv);
    // A vertex that is no sample is skipped (as VertexPlanes of the dense fit).
    if (!is_sample_point(Xf)) continue;
    const Vector3 X = Xf.template cast<Scalar>();
    const QuadricLinearization<Scalar> l = linearize_quadric(q, X);
    const Scalar d2 = (X - q.center).squaredNorm();
    if (!(l.r <= limits.gate && l.r >= -limits.gate)) {
      ne.add_outside(fair_weight(limits.gate, d2, limits.n0), limits.gate);
      continue;
    }
    ne.add(l.J, l.r, fair_weight(l.r, d2, limits.n0));
  }
}

/// The column scales of Quad IT's system in units of the centre's range d = |p̄| (lengths over
/// d: Δω, Δt_z / d, Δκ · d), so that Δ = S Δ' with S = diag(1, 1, d, 1/d, 1/d, 1/d). In these
/// units a scene scaled by s (d, ρ → s d, s ρ) gives the same system: the curvature columns, which
/// grow as ρ² against the offset's 1, no longer fall below the singularity floor at near range.
/// At d = 1 m S is the identity.
JPCR_HD void range_unit_scales(double range, double S[6]) {
  S[0] = S[1] = 1.0;
  S[2] = range;
  S[3] = S[4] = S[5] = 1.0 / range;
}

/// The undamped system of a pixel is singular when a pivot of its unit-diagonal form falls below
/// this (unit_diagonal_regular): the samples do not tell some combination of tilt, offset and
/// curvature apart. Two pattern columns on a thin pole or a 2-px strip (x² is then affine in x)
/// give 1e-16 in double (review of 2026-12-06), and stay below this with the lanes' float sums
/// (test ATwoColumnStripIsSingularInTheLanesAndTheKernel). The damping used to hide such a system,
/// and the pixel came back valid with a curvature the samples never saw (κ₂ = −0.5 1/m on a
/// plane, −0.15 on a pole of −167). Measured on jpcr_synth --frames 3 --size 320x240 --seed 1
/// (Quad IT, all pixels): 1e-6 takes 94 of 221 891 valid pixels noise-free in room_spheres (their
/// RMS error 16.8 1/m; all pixels 2.136 → 2.122) and 58 in cylinders_boxes, 0–15 at 1 % range
/// noise; 1e-4 took 777 and 466, half of them with errors below 0.05 1/m.
constexpr double kSingularPivot = 1e-6;

/// Solves the damped system (H + λ diag H) Δ = −g in double (method.md §10: the step carries the
/// minus sign the paper drops), as S H S + λ diag(S H S)) Δ' = −S g, Δ = S Δ' in the range units
/// of range_unit_scales (the same step: the damping on the diagonal is invariant to column
/// scales). Returns false when the undamped system is singular (kSingularPivot), the damped one
/// fails cholesky_factor's floor, or the step is not finite.
template <typename Scalar>
JPCR_HD bool solve_damped_step(const NormalEquations6<Scalar>& ne, double damping, double range,
                               Eigen::Matrix<double, 6, 1>& delta) {
  double S[6];
  range_unit_scales(range, S);
  Eigen::Matrix<double, 6, 6> H;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j <= i; ++j)
      H(i, j) = S[i] * double(ne.H(i, j)) * S[j];
    delta(i) = -S[i] * double(ne.g(i));
  }
  if (!unit_diagonal_regular<double, 6>(H, kSingularPivot)) return false;
  for (int i = 0; i < 6; ++i)
    H(i, i) *= 1.0 + damping;
  if (!cholesky_factor<double, 6>(H)) return false;
  cholesky_solve<double, 6>(H, delta);
  for (int i = 0; i < 6; ++i) {
    delta(i) *= S[i];
    if (!(delta(i) - delta(i) == 0.0)) return false;
  }
  return true;
}

/// Whether `centre` can be a quadric's p̄: a sample (is_sample_point) with a range |p̄| > 0 (the
/// fit's range units); `range` gets |p̄| in double, the same in the per-pixel and the lane-parallel
/// fit.
JPCR_HD bool centre_with_range(const Eigen::Vector3f& centre, double& range) {
  if (!is_sample_point(centre)) return false;
  const double x = centre.x(), y = centre.y(), z = centre.z();
  range = std::sqrt(x * x + y * y + z * z);
  return range > 0.0;
}

/// The early stop of Quad IT: every part of the step below its tolerance.
JPCR_HD bool step_converged(const Eigen::Matrix<double, 6, 1>& delta, const QuadricFitParams& p) {
  const double dw = delta(0) * delta(0) + delta(1) * delta(1);
  const double dk = fmax(fabs(delta(3)), fmax(fabs(delta(4)), fabs(delta(5))));
  return dw < double(p.angle_tolerance) * p.angle_tolerance &&
         fabs(delta(2)) < p.offset_tolerance && dk < p.curvature_tolerance;
}

/// The damping of a retried first step: the first step from the plane that raised the cost is
/// retried from the plane with the damping times this, while passes remain.
constexpr double kRetryDampingFactor = 10.0;

/// Quad IT at pixel (u, v): starts from the plane of `normal` at p̄ = vertices(u, v) and runs up
/// to p.iterations Gauss-Newton passes. A step is kept only if it does not raise the gated cost
/// Σ w(e) e² (NormalEquations6::gated; the Levenberg-Marquardt safeguard: under range noise the
/// undamped rotation steps can overshoot). The mean over the inliers, compared before, rose for
/// a step that took in more samples though the fit improved. A later step that raises it is undone
/// and the fit stops with the steps before it; the first one is retried from the plane with the
/// damping times kRetryDampingFactor, since the plane is a start, not a fit. When no step is ever
/// kept the pixel is kNoStep (its curvature would be the start's 0, method.md §3). On kValid, q
/// holds the fitted quadric.
template <typename Scalar>
JPCR_HD QuadricStatus fit_quadric_pixel(const VertexView& vertices, const PixelOffset* pattern,
                                        int pattern_size, int u, int v,
                                        const Eigen::Vector3f& normal, const QuadricFitParams& p,
                                        QuadricT<Scalar>& q) {
  const Eigen::Vector3f& centre = vertices(u, v);
  double range = 0.0;
  if (!centre_with_range(centre, range)) return QuadricStatus::kNoCentre;
  if (!is_finite_value(normal.z())) return QuadricStatus::kNoNormal;
  q.R = local_frame<Scalar>(normal.template cast<Scalar>().normalized());
  q.center = centre.template cast<Scalar>();
  q.t_z = q.a = q.b = q.c = Scalar(0);
  QuadricT<Scalar> previous = q;
  double previous_cost = 1e300;
  double damping = p.damping;
  bool kept = p.iterations == 0;  // a step was kept (no steps asked: the plane is the answer)
  bool stepped = false;           // q is a step from `previous` that no pass has checked yet
  // One pass more than steps: the last pass only checks the last step's cost.
  for (int it = 0; it <= p.iterations; ++it) {
    NormalEquations6<Scalar> ne;
    accumulate_quadric_samples(q, vertices, pattern, pattern_size, u, v, p, ne);
    const double cost = double(ne.gated);
    const bool too_few = ne.count < p.min_samples;
    // A step that made the fit worse, or left fewer than min_samples inliers (method.md §3: a
    // fit on fewer is invalid), is undone; the fit stops, or retries the first step damped.
    if (stepped && (cost > previous_cost || too_few)) {
      q = previous;
      stepped = false;
      if (kept) break;
      damping *= kRetryDampingFactor;
      continue;  // the next pass sums at the plane again and steps from it
    }
    if (too_few) return QuadricStatus::kTooFewSamples;  // the starting plane
    kept = kept || stepped;
    if (it == p.iterations) break;
    previous = q;
    previous_cost = cost;
    Eigen::Matrix<double, 6, 1> delta;
    if (!solve_damped_step(ne, damping, range, delta)) return QuadricStatus::kSingular;
    apply_quadric_update(q, QuadricVector<Scalar>(delta.template cast<Scalar>()));
    stepped = true;
    if (step_converged(delta, p)) {
      kept = true;  // a step this small: the fit is where it stands
      break;
    }
  }
  return kept ? QuadricStatus::kValid : QuadricStatus::kNoStep;
}

}  // namespace jpcr
