// The spread of a curvature map under the sensor's noise: per pixel, how far the fitted (κ₁, κ₂)
// may lie from the surface's because the samples it was fitted to are noisy. A map that says
// only "valid" leaves a user to guess whether 3 1/m is a curve or noise at 2 % range noise; this
// says which (README, "Curvature spread").
//
//   QuadricMap map = QuadricFit(params).estimate(vertices);
//   Image<float> sd = curvature_spread(map, vertices, params.pattern_for(vertices.width()),
//                                      params.fit);
//
// At each valid pixel the fit's own samples (its pattern on `vertices`, inside the gate, Fair
// weights w at the fitted quadric: method.md §3) give the weighted least-squares sandwich
//
//   Cov(γ) = n / (n − 6) · H⁻¹ (Σ w² r² J Jᵀ) H⁻¹,   H = Σ w J Jᵀ,
//
// the covariance of a weighted fit whose weights are held, with each sample's own squared
// residual for its variance (it needs no noise model, and a residual that the quadric cannot
// explain, at a crease, counts as noise). K = [[a, b], [b, c]] holds the curvature (method.md §3
// "Output"), and by the Hoffman–Wielandt inequality (κ₁' − κ₁)² + (κ₂' − κ₂)² ≤ ‖K' − K‖²_F for
// any perturbed K', so
//
//   sd = √((Var a + 2 Var b + Var c) / 2)
//
// bounds the RMS over the two curvatures of their error from the parameters' spread, without
// linearising the eigenvalues (exact at an umbilic, a sphere, where they are not differentiable).
// It is comparable with jpcr_eval curvature's "rms".
//
// Only where at least kMinInsideFraction of the pixel's samples lie inside the gate: the
// residuals inside it are then the noise's, truncated at 1.64 σ or more for Gaussian noise (their
// variance then low by 38 %, the sd by 21 %, at most). Where more fall outside, the fit's data are
// not a sample of the noise: a depth edge or crease in the pattern, or a gate below the noise
// (the built-in 14 mm under 1 % range noise at 2 m), where the sd would be half the error.
//
// What it does not describe: a bias (the model's dropped terms, regression dilution under heavy
// range noise, a fit bent across a crease whose residuals look small), and the other frames'
// samples of a J-ftf or J-full fit: their maps get the spread of their final quadrics on their
// own keyframe's samples, the single-frame value.
#pragma once

#include "jpcr/quadric/image.hpp"
#include "jpcr/quadric/neighbourhood_pattern.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"
#include "jpcr/quadric/quadric_map.hpp"
#include "jpcr/quadric/quadric_params.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

/// The share of a pixel's samples that must lie inside the gate for an sd (above).
inline constexpr double kMinInsideFraction = 0.9;

/// sd (1/m) at every valid pixel of `map` (above); NaN where the map is invalid, where fewer than
/// fit.min_samples or kMinInsideFraction of the samples are inside the gate, or where the system
/// is singular. `vertices` are
/// the frame the map was fitted on, `pattern` and `fit` its parameters. Parallel over rows.
/// Throws InputError when map and vertices differ in size.
Image<float> curvature_spread(const QuadricMap& map, const VertexMap& vertices,
                              const NeighbourhoodPattern& pattern, const QuadricFitParams& fit);

/// The same with the pattern and fit of the parameters the map was made with (the pattern at
/// the width of `vertices`), as the curvature writers and the DDS publisher call it.
inline Image<float> curvature_spread(const QuadricMap& map, const VertexMap& vertices,
                                     const QuadricParams& params) {
  return curvature_spread(map, vertices, params.pattern_for(vertices.width()), params.fit);
}

/// The same at one pixel, in double: NaN where curvature_spread gives NaN.
double curvature_spread_at(const QuadricMap& map, const VertexMap& vertices,
                           const NeighbourhoodPattern& pattern, const QuadricFitParams& fit, int u,
                           int v);

}  // namespace jpcr
