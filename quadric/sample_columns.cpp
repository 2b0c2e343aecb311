#include "jpcr/quadric/sample_columns.hpp"

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

// Dot products along the samples, four at a time so that each load of column a serves four.
template <typename Lane>
JPCR_SIMD_CLONES void products(const Lane* columns, int n, int stride, int cols, double* Y) {
  using Vec = typename LaneVector<Lane>::type;
  constexpr int kLanes = sizeof(Vec) / sizeof(Lane);
  const auto col = [columns, stride](int c) {
    return columns + static_cast<std::size_t>(c) * stride;
  };
  const auto total = [](const Vec& t) {
    double sum = 0.0;
    for (int lane = 0; lane < kLanes; ++lane)
      sum += t[lane];
    return sum;
  };
  for (int a = 0; a < cols; ++a) {
    const Lane* ca = col(a);
    int b = 0;
    for (; b + 3 <= a; b += 4) {
      const Lane *c0 = col(b), *c1 = col(b + 1), *c2 = col(b + 2), *c3 = col(b + 3);
      Vec t0 = {}, t1 = {}, t2 = {}, t3 = {};
      for (int k = 0; k < n; k += kLanes) {
        Vec x, y0, y1, y2, y3;
        load_lanes(x, ca + k);
        load_lanes(y0, c0 + k);
        load_lanes(y1, c1 + k);
        load_lanes(y2, c2 + k);
        load_lanes(y3, c3 + k);
        t0 += x * y0;
        t1 += x * y1;
        t2 += x * y2;
        t3 += x * y3;
      }
      Y[a * 10 + b] = Y[b * 10 + a] = total(t0);
      Y[a * 10 + b + 1] = Y[(b + 1) * 10 + a] = total(t1);
      Y[a * 10 + b + 2] = Y[(b + 2) * 10 + a] = total(t2);
      Y[a * 10 + b + 3] = Y[(b + 3) * 10 + a] = total(t3);
    }
    for (; b <= a; ++b) {
      const Lane* cb = col(b);
      Vec t = {};
      for (int k = 0; k < n; k += kLanes) {
        Vec x, y;
        load_lanes(x, ca + k);
        load_lanes(y, cb + k);
        t += x * y;
      }
      Y[a * 10 + b] = Y[b * 10 + a] = total(t);
    }
  }
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
