// Quad IT's normal equations for kPixelLanes horizontally adjacent pixels at once, one pixel
// per SIMD lane: one pass over the neighbourhood pattern linearises each pixel's samples, gates
// and weights them (method.md §3) and adds w (y, r)(y, r)ᵀ into registers, the column products
// of sample_columns.hpp without storing the columns. AVX-512 where the CPU has it, else AVX2 +
// FMA, else the baseline (pixel_lane_sums.inc, once per target).
// tests/quadric/test_pixel_lane_sums.cpp compares every level with a per-sample double sum.
#pragma once

#include <cstddef>

#include "jpcr/quadric/sample_columns.hpp"
#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

/// Pixels fitted together, one per lane.
constexpr int kPixelLanes = 16;
/// The lower triangle of the 7 x 7 column products: (a, b ≤ a) at a (a + 1) / 2 + b.
constexpr int kQuadricProducts = kQuadricColumns * (kQuadricColumns + 1) / 2;

/// One pass's inputs, lane by lane: each pixel's quadric (R row-major, t_z, a, b, c, in
/// coordinates centred on p̄), its centre p̄, and its gate and n₀ (SampleGate).
struct PixelLaneQuadrics {
  float R[9][kPixelLanes];
  float t_z[kPixelLanes], a[kPixelLanes], b[kPixelLanes], c[kPixelLanes];
  float centre[3][kPixelLanes];
  float gate[kPixelLanes], n0[kPixelLanes];
};

/// Each lane's sums: Y = Σ w (y, r)(y, r)ᵀ as kQuadricProducts entries (lower triangle, in the
/// column order of SampleColumn), Σ w(e) e² over all samples, Σ w r² over the inliers and the
/// number of inliers (the three of SampleCosts).
struct PixelLaneSums {
  float products[kQuadricProducts][kPixelLanes];
  float gated[kPixelLanes], inliers[kPixelLanes], count[kPixelLanes];
};

/// The sums of one pass. x, y and z point at the first pixel's vertex in three float planes of
/// one row stride; the pixel in lane l is l floats further on, and its sample k lies offsets[k]
/// floats from it in each plane. Samples whose z is not finite are skipped, so planes with a
/// NaN margin implement the 2-D bounds check (method.md §2); x and y must be finite wherever z
/// is (a NaN there would reach the lane's sums). Products only where
/// with_products. Throws std::invalid_argument for a level above cpu_simd_level().
void pixel_lane_sums(const PixelLaneQuadrics& q, const float* x, const float* y, const float* z,
                     const std::ptrdiff_t* offsets, int n, bool with_products, PixelLaneSums& out,
                     SimdLevel level = cpu_simd_level());

}  // namespace jpcr
