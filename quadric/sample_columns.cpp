#include "jpcr/quadric/sample_columns.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

// One sample's gated weight and cost shares, branch-free (method.md §3: the residual gate, the
// fair weight w = n₀² / (n₀² + r² + d²)).
template <typename Lane>
inline void gate_sample(Lane r, Lane d2, Lane mask, Lane gate, Lane n0, Lane& inside, Lane& w,
                        Lane& gated_cost) {
  inside = mask * (std::abs(r) <= gate ? Lane(1) : Lane(0));
  const Lane e = inside > Lane(0) ? r : gate;
  const Lane we = fair_weight(e, d2, n0);
  gated_cost = mask * we * e * e;
  w = inside * we;
}

// The same cost share with the weight held: `held` is r_h² + d² of the weight at the
// linearisation (GatheredFrameTerms::held_cost), so w = n₀² / (n₀² + held).
template <typename Lane>
inline void held_sample(Lane r, Lane held, Lane mask, Lane gate, Lane n0, Lane& inside,
                        Lane& gated_cost) {
  inside = mask * (std::abs(r) <= gate ? Lane(1) : Lane(0));
  const Lane e = inside > Lane(0) ? r : gate;
  gated_cost = mask * fair_weight(Lane(0), held, n0) * e * e;
}

template <typename Lane, int kColumns>
JPCR_SIMD_CLONES SampleCosts fill_columns(const QuadricScalars<Lane>& qs, const Lane* __restrict dx,
                                          const Lane* __restrict dy, const Lane* __restrict dz,
                                          const Lane* __restrict d2, const Lane* __restrict mask,
                                          int n, Lane gate, Lane n0, int stride, Lane* columns,
                                          Lane ox, Lane oy, Lane oz, Lane min_cos2) {
  static_assert(kColumns == kQuadricColumns || kColumns == kPoseColumns, "column set");
  const auto col = [columns, stride](int c) {
    return columns + static_cast<std::size_t>(c) * stride;
  };
  Lane* __restrict one = col(kColOne);
  Lane* __restrict j0 = col(kColJ0);
  Lane* __restrict j1 = col(kColJ1);
  Lane* __restrict j3 = col(kColJ3);
  Lane* __restrict j4 = col(kColJ4);
  Lane* __restrict j5 = col(kColJ5);
  Lane* __restrict res = col(kColR);
  Lane* __restrict gx = kColumns == kPoseColumns ? col(kColGx) : nullptr;
  Lane* __restrict gy = kColumns == kPoseColumns ? col(kColGy) : nullptr;
  Lane* __restrict m = kColumns == kPoseColumns ? col(kColM) : nullptr;
  constexpr int kLanes = 32 / sizeof(Lane);  // one AVX register
  Lane gated_sum = 0, inlier_sum = 0, count_sum = 0;
#pragma omp simd simdlen(kLanes) reduction(+ : gated_sum, inlier_sum, count_sum)
  for (int k = 0; k < n; ++k) {
    const SampleLinearization<Lane> l = linearize_sample(qs, dx[k], dy[k], dz[k]);
    Lane inside, w, c;
    gate_sample(l.r, d2[k], mask[k], gate, n0, inside, w, c);
    gated_sum += c;
    inlier_sum += w * l.r * l.r;
    count_sum += inside;
    const Lane sw = std::sqrt(w);
    Lane m0 = l.J0, m1 = l.J1, m2 = 0;
    if constexpr (kColumns == kPoseColumns)
      ray_foot_moment(l.r, l.vx, l.vy, l.vz, l.gx, l.gy, l.vx + ox, l.vy + oy, l.vz + oz, min_cos2,
                      m0, m1, m2);
    one[k] = sw;
    j0[k] = sw * m0;
    j1[k] = sw * m1;
    j3[k] = sw * l.J3;
    j4[k] = sw * l.J4;
    j5[k] = sw * l.J5;
    res[k] = sw * l.r;
    if constexpr (kColumns == kPoseColumns) {
      gx[k] = sw * l.gx;
      gy[k] = sw * l.gy;
      m[k] = sw * m2;  // (v × g)_z at the foot point
    }
  }
  return {gated_sum, inlier_sum, static_cast<int>(count_sum)};
}

template <typename Lane>
JPCR_SIMD_CLONES SampleCosts costs(const QuadricScalars<Lane>& qs, const Lane* __restrict dx,
                                   const Lane* __restrict dy, const Lane* __restrict dz,
                                   const Lane* __restrict d2, const Lane* __restrict mask, int n,
                                   Lane gate, Lane n0) {
  constexpr int kLanes = 32 / sizeof(Lane);  // one AVX register
  Lane gated_sum = 0, inlier_sum = 0, count_sum = 0;
#pragma omp simd simdlen(kLanes) reduction(+ : gated_sum, inlier_sum, count_sum)
  for (int k = 0; k < n; ++k) {
    const SampleLinearization<Lane> l = linearize_sample(qs, dx[k], dy[k], dz[k]);
    Lane inside, w, c;
    gate_sample(l.r, d2[k], mask[k], gate, n0, inside, w, c);
    gated_sum += c;
    inlier_sum += w * l.r * l.r;
    count_sum += inside;
  }
  return {gated_sum, inlier_sum, static_cast<int>(count_sum)};
}

template <typename Lane>
JPCR_SIMD_CLONES SampleCosts held_costs(const QuadricScalars<Lane>& qs, const Lane* __restrict dx,
                                        const Lane* __restrict dy, const Lane* __restrict dz,
                                        const Lane* __restrict held, const Lane* __restrict mask,
                                        int n, Lane gate, Lane n0) {
  constexpr int kLanes = 32 / sizeof(Lane);  // one AVX register
  Lane gated_sum = 0, count_sum = 0;
#pragma omp simd simdlen(kLanes) reduction(+ : gated_sum, count_sum)
  for (int k = 0; k < n; ++k) {
    const SampleLinearization<Lane> l = linearize_sample(qs, dx[k], dy[k], dz[k]);
    Lane inside, c;
    held_sample(l.r, held[k], mask[k], gate, n0, inside, c);
    gated_sum += c;
    count_sum += inside;
  }
  return {gated_sum, 0.0, static_cast<int>(count_sum)};
}

// A register of lanes (GCC/Clang vector extension; the baseline clone splits it in two).
template <typename Lane>
struct LaneVector {
  typedef Lane type __attribute__((vector_size(32)));
};

// Unaligned load of one register (by reference: a 32-byte vector is never passed by value,
// its ABI differs between the AVX and baseline clones).
template <typename Vec, typename Lane>
inline void load_lanes(Vec& x, const Lane* p) {
  std::memcpy(&x, p, sizeof(Vec));
}

// Σ of each of two registers' lanes, in double. The float lanes are widened and summed pairwise,
// which equals their sum one by one up to double rounding (none while their magnitudes lie
// within about 2^26 of each other). __builtin_shufflevector: GCC 12, clang.
template <typename Vec>
inline void totals(const Vec& t, const Vec& u, double& sum_t, double& sum_u) {
  if constexpr (sizeof(t[0]) == sizeof(float)) {
    typedef double Wide __attribute__((vector_size(32)));
    const Wide a = __builtin_convertvector(__builtin_shufflevector(t, t, 0, 1, 2, 3), Wide) +
                   __builtin_convertvector(__builtin_shufflevector(t, t, 4, 5, 6, 7), Wide);
    const Wide b = __builtin_convertvector(__builtin_shufflevector(u, u, 0, 1, 2, 3), Wide) +
                   __builtin_convertvector(__builtin_shufflevector(u, u, 4, 5, 6, 7), Wide);
    const Wide h =
        __builtin_shufflevector(a, b, 0, 4, 2, 6) + __builtin_shufflevector(a, b, 1, 5, 3, 7);
    sum_t = h[0] + h[2];
    sum_u = h[1] + h[3];
  } else {
    sum_t = ((t[0] + t[1]) + t[2]) + t[3];
    sum_u = ((u[0] + u[1]) + u[2]) + u[3];
  }
}

// The 2 x 4 block of Y at rows a, a + 1 and columns b..b + 3: 6 loads serve 8 products, and the
// 8 sums are independent (no sum waits for the one before). Rows and columns at or past `cols`
// read the last column instead, and their sums are not stored.
template <typename Lane>
__attribute__((always_inline)) inline void product_block(const Lane* columns, int n, int stride,
                                                         int cols, int a, int b, double* Y) {
  using Vec = typename LaneVector<Lane>::type;
  constexpr int kLanes = sizeof(Vec) / sizeof(Lane);
  constexpr int R = 2, C = 4;
  const auto col = [&](int c) {
    return columns + static_cast<std::size_t>(std::min(c, cols - 1)) * stride;
  };
  const Lane* ca[R] = {col(a), col(a + 1)};
  const Lane* cb[C] = {col(b), col(b + 1), col(b + 2), col(b + 3)};
  Vec t[R * C] = {};  // t[r * C + c]: the sum of rows a + r and b + c
  for (int k = 0; k < n; k += kLanes) {
    Vec x[R], y[C];
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r)
      load_lanes(x[r], ca[r] + k);
#pragma GCC unroll 4
    for (int c = 0; c < C; ++c)
      load_lanes(y[c], cb[c] + k);
#pragma GCC unroll 4
    for (int r = 0; r < R; ++r)
#pragma GCC unroll 4
      for (int c = 0; c < C; ++c)
        t[r * C + c] += x[r] * y[c];
  }
  double sums[R * C];
  for (int i = 0; i < R * C; i += 2)
    totals(t[i], t[i + 1], sums[i], sums[i + 1]);
  for (int r = 0; r < R && a + r < cols; ++r)
    for (int c = 0; c < C && b + c < cols; ++c)
      Y[(a + r) * 10 + b + c] = Y[(b + c) * 10 + a + r] = sums[r * C + c];
}

// Dot products along the samples in blocks of 2 rows x 4 columns up to the diagonal. A block
// across it computes a few products of the upper triangle too: the same lanes in the same order,
// so both triangles get the same sums.
template <typename Lane>
JPCR_SIMD_CLONES void products(const Lane* columns, int n, int stride, int cols, double* Y) {
  for (int a = 0; a < cols; a += 2)
    for (int b = 0; b <= std::min(a + 1, cols - 1); b += 4)
      product_block<Lane>(columns, n, stride, cols, a, b, Y);
}

}  // namespace

template <typename Lane, int kColumns>
SampleCosts fill_sample_columns(const QuadricScalars<Lane>& qs, const GatheredSamples<Lane>& s,
                                Lane gate, Lane n0, int stride, Lane* columns,
                                const RayFoot<Lane>& foot) {
  return fill_columns<Lane, kColumns>(qs, s.dx, s.dy, s.dz, s.d2, s.mask, s.n, gate, n0, stride,
                                      columns, foot.ox, foot.oy, foot.oz, foot.min_cos2);
}

template <typename Lane>
SampleCosts sample_costs(const QuadricScalars<Lane>& qs, const GatheredSamples<Lane>& s, Lane gate,
                         Lane n0) {
  return costs<Lane>(qs, s.dx, s.dy, s.dz, s.d2, s.mask, s.n, gate, n0);
}

template <typename Lane>
SampleCosts held_sample_costs(const QuadricScalars<Lane>& qs, const GatheredSamples<Lane>& s,
                              Lane gate, Lane n0) {
  return held_costs<Lane>(qs, s.dx, s.dy, s.dz, s.d2, s.mask, s.n, gate, n0);
}

template <typename Lane>
void column_products(const Lane* columns, int n, int stride, int cols, double* Y) {
  products<Lane>(columns, n, stride, cols, Y);
}

template SampleCosts fill_sample_columns<float, kQuadricColumns>(const QuadricScalars<float>&,
                                                                 const GatheredSamples<float>&,
                                                                 float, float, int, float*,
                                                                 const RayFoot<float>&);
template SampleCosts fill_sample_columns<float, kPoseColumns>(const QuadricScalars<float>&,
                                                              const GatheredSamples<float>&, float,
                                                              float, int, float*,
                                                              const RayFoot<float>&);
template SampleCosts fill_sample_columns<double, kQuadricColumns>(const QuadricScalars<double>&,
                                                                  const GatheredSamples<double>&,
                                                                  double, double, int, double*,
                                                                  const RayFoot<double>&);
template SampleCosts fill_sample_columns<double, kPoseColumns>(const QuadricScalars<double>&,
                                                               const GatheredSamples<double>&,
                                                               double, double, int, double*,
                                                               const RayFoot<double>&);
template SampleCosts sample_costs<float>(const QuadricScalars<float>&,
                                         const GatheredSamples<float>&, float, float);
template SampleCosts sample_costs<double>(const QuadricScalars<double>&,
                                          const GatheredSamples<double>&, double, double);
template SampleCosts held_sample_costs<float>(const QuadricScalars<float>&,
                                              const GatheredSamples<float>&, float, float);
template SampleCosts held_sample_costs<double>(const QuadricScalars<double>&,
                                               const GatheredSamples<double>&, double, double);
template void column_products<float>(const float*, int, int, int, double*);
template void column_products<double>(const double*, int, int, int, double*);

}  // namespace jpcr
