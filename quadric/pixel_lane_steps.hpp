// The per-pixel halves of a Quad IT iteration for kPixelLanes pixels at once, with the lane as
// the innermost index so that they vectorise across pixels (quadric_fit.cpp): the damped
// Gauss-Newton step of each lane's normal equations, and the update γ ← γ ⊕ Δγ. Same math as
// solve_damped_step, apply_quadric_update and step_converged (quadric_fit_kernel.hpp,
// quadric_model.hpp), which tests/quadric/test_pixel_lane_steps.cpp compares them with.
#pragma once

#include "jpcr/quadric/pixel_lane_sums.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"

namespace jpcr {

/// The quadrics of kPixelLanes pixels in rows of lanes: R row-major in rows 0–8, then t_z, a,
/// b, c (coordinates centred on each lane's p̄).
struct LaneQuadrics {
  static constexpr int kRows = 13;
  static constexpr int kTz = 9, kA = 10, kB = 11, kC = 12;
  double row[kRows][kPixelLanes];
};

/// Each lane's step (H + λ_l diag H) Δ = −g, with H = Σ w J Jᵀ and g = Σ w J r read off its
/// sums (kGammaColumn, kGammaSign) and λ_l = damping[l], solved by LDLᵀ in double in the range
/// units of range_unit_scales (range[l] = |p̄| of lane l, m) with cholesky_factor's pivot test, as
/// solve_damped_step. ok[l] is false where lane l's H is not numerically positive definite or Δ
/// is not finite.
void pixel_lane_steps(const PixelLaneSums& sums, const double damping[kPixelLanes],
                      const double range[kPixelLanes], double delta[6][kPixelLanes],
                      bool ok[kPixelLanes]);

/// γ ← γ ⊕ Δγ where take[l]: R ← exp([Δω₁, Δω₂, 0]×) R (Rodrigues: sin θ / θ and
/// (1 − cos θ) / θ² from their series, exact in double, for θ ≤ 0.5 rad, from std::sin and
/// std::cos above), then t_z, a, b, c added. converged[l] is step_converged(Δ) for every lane.
void pixel_lane_updates(LaneQuadrics& q, const double delta[6][kPixelLanes],
                        const bool take[kPixelLanes], const QuadricFitParams& p,
                        bool converged[kPixelLanes]);

}  // namespace jpcr
