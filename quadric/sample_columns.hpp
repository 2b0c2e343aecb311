// The per-sample SIMD loops of the joint systems' gathered per-frame sums
// (backend/gathered_frame_terms.cpp; Quad IT has its own, pixel_lane_sums.hpp, with the same
// columns). They linearise the samples of one neighbourhood, gathered into contiguous lane
// arrays d = X − p̄ (d², and a mask 0 for padding), and read their normal equations off one
// small matrix of column products.
//
// With v = R d, g = (g_x, g_y, −1) and m = v_x g_y − v_y g_x (quadric_model.hpp), the columns
// are √w times y = (1, J₀, J₁, J₃, J₄, J₅), r, then the pose-only entries (g_x, g_y, m); w is the
// gated fair weight of method.md §3. So J_γ = (J₀, J₁, −1, J₃, J₄, J₅) is kGammaColumn with
// kGammaSign, and Y = Σ w (y, r)(y, r)ᵀ holds Σ w J_γ J_γᵀ, Σ w J_γ r and Σ w r² (inliers).
#pragma once

#include "jpcr/quadric/quadric_model.hpp"

namespace jpcr {

enum SampleColumn { kColOne, kColJ0, kColJ1, kColJ3, kColJ4, kColJ5, kColR, kColGx, kColGy, kColM };
constexpr int kQuadricColumns = 7;  // J_γ and r: Quad IT and the frame-1 terms
constexpr int kPoseColumns = 10;    // and (g_x, g_y, m) for the pose Jacobian

/// J_γ entry i as (column, sign).
constexpr int kGammaColumn[6] = {kColJ0, kColJ1, kColOne, kColJ3, kColJ4, kColJ5};
constexpr double kGammaSign[6] = {1, 1, -1, 1, 1, 1};

/// The gathered samples of one neighbourhood: n is a multiple of the lane count, padding has
/// mask 0. Arrays of n lanes each.
template <typename Lane>
struct GatheredSamples {
  const Lane *dx, *dy, *dz, *d2, *mask;
  int n;
};

/// The sums besides the columns: Σ over all samples of the gated cost w(e) e² with e = r inside
/// the gate and the gate outside (the joint systems' cost), Σ w r² over the inliers (Quad IT's
/// cost), and the number of inliers.
struct SampleCosts {
  double gated = 0.0;
  double inliers = 0.0;
  int count = 0;
};

/// The foot points of the samples' rays (ray_foot_moment, quadric_model.hpp) for the pose
/// columns: the sample's camera centre o as p̄ − o in the quadric's local axes, and cos²_min
/// (kNoRayFoot: the lever arms stay at the samples).
template <typename Lane>
struct RayFoot {
  Lane ox = 0, oy = 0, oz = 0;
  Lane min_cos2 = Lane(kNoRayFoot);
};

/// Writes the first kColumns columns (√w (y, r), stride lanes apart) for quadric qs and returns
/// the costs. kColumns is kQuadricColumns or kPoseColumns; the pose columns take J₀, J₁ and m at
/// the rays' foot points (`foot`), the quadric columns at the samples.
template <typename Lane, int kColumns>
SampleCosts fill_sample_columns(const QuadricScalars<Lane>& qs, const GatheredSamples<Lane>& s,
                                Lane gate, Lane n0, int stride, Lane* columns,
                                const RayFoot<Lane>& foot = {});

/// The costs alone (no columns).
template <typename Lane>
SampleCosts sample_costs(const QuadricScalars<Lane>& qs, const GatheredSamples<Lane>& s, Lane gate,
                         Lane n0);

/// The gated cost Σ w e² with each sample's weight held: s.d2 holds r_h² + d² of the weight
/// n₀² / (n₀² + r_h² + d²) at another state (the joint systems' step test); `inliers` is 0.
template <typename Lane>
SampleCosts held_sample_costs(const QuadricScalars<Lane>& qs, const GatheredSamples<Lane>& s,
                              Lane gate, Lane n0);

/// Y = Σ_k c_k c_kᵀ over the first `cols` ≤ 10 columns (n samples, stride lanes apart), into the
/// row-major 10 x 10 array Y (both triangles of its top-left cols x cols), accumulated in lanes
/// and summed in double. n is a multiple of one register's lanes (32 bytes) and ≤ stride, the
/// samples past the gathered ones zero (GatheredFrameTerms, CurvatureSpread pad them so).
template <typename Lane>
void column_products(const Lane* columns, int n, int stride, int cols, double* Y);

}  // namespace jpcr
