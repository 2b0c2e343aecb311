#include "jpcr/backend/gathered_frame_terms.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

// The columns of Y (file comment of the header): y = (1, J₀, J₁, J₃, J₄, J₅), r, then the
// pose-only entries (g_x, g_y, m).
enum Column { kOne, kJ0, kJ1, kJ3, kJ4, kJ5, kR, kGx, kGy, kM };
constexpr int kQuadricColumns = 7;  // frame-1 terms: J_γ and r

// J_γ = (J₀, J₁, −1, J₃, J₄, J₅) and J_loc = (g_x, g_y, −1, J₀, J₁, m) as (column, sign).
constexpr int kGammaColumn[6] = {kJ0, kJ1, kOne, kJ3, kJ4, kJ5};
constexpr double kGammaSign[6] = {1, 1, -1, 1, 1, 1};
constexpr int kLocalColumn[6] = {kGx, kGy, kOne, kJ0, kJ1, kM};
constexpr double kLocalSign[6] = {1, 1, -1, 1, 1, 1};

}  // namespace

namespace {

// d = R Q + o and |d|² for the n gathered points, in double, stored as lanes.
template <typename Lane>
JPCR_SIMD_CLONES void centre_samples(const double* R, const double* o, int n, const float* qx,
                                     const float* qy, const float* qz, Lane* __restrict dx,
                                     Lane* __restrict dy, Lane* __restrict dz,
                                     Lane* __restrict d2) {
  for (int k = 0; k < n; ++k) {
    const double x = qx[k], y = qy[k], z = qz[k];
    const double ex = R[0] * x + R[3] * y + R[6] * z + o[0];  // R is column-major
    const double ey = R[1] * x + R[4] * y + R[7] * z + o[1];
    const double ez = R[2] * x + R[5] * y + R[8] * z + o[2];
    dx[k] = static_cast<Lane>(ex);
    dy[k] = static_cast<Lane>(ey);
    dz[k] = static_cast<Lane>(ez);
    d2[k] = static_cast<Lane>(ex * ex + ey * ey + ez * ez);
  }
}

}  // namespace

template <typename Lane>
int GatheredFrameTerms<Lane>::gather(const VertexView& view, const RigidMotion<double>& T,
                                     const PixelOffset* pattern, int pattern_size, int u, int v,
                                     const Eigen::Vector3d& centre) {
  float *qx = raw_.data(), *qy = qx + capacity_, *qz = qy + capacity_;
  int n = 0;
  if (pattern != pattern_ || view.width != pattern_width_) {  // once per pattern and image width
    reach_ = 0;
    linear_.resize(static_cast<std::size_t>(pattern_size));
    for (int k = 0; k < pattern_size; ++k) {
      reach_ = std::max({reach_, std::abs(pattern[k].du), std::abs(pattern[k].dv)});
      linear_[k] = static_cast<std::ptrdiff_t>(pattern[k].dv) * view.width + pattern[k].du;
    }
    pattern_ = pattern;
    pattern_width_ = view.width;
  }
  const Eigen::Vector3f* row = view.data + static_cast<std::ptrdiff_t>(v) * view.width + u;
  if (u >= reach_ && v >= reach_ && u + reach_ < view.width && v + reach_ < view.height) {
    // The whole pattern is in the image: no bounds checks, and a branch-free compaction (each
    // point is written, the count advances only past finite ones).
    for (int k = 0; k < pattern_size; ++k) {
      const Eigen::Vector3f& Q = row[linear_[k]];
      qx[n] = Q.x();
      qy[n] = Q.y();
      qz[n] = Q.z();
      n += is_finite_value(Q.z()) ? 1 : 0;
    }
  } else {
    for (int k = 0; k < pattern_size; ++k) {
      const int su = u + pattern[k].du, sv = v + pattern[k].dv;
      if (!view.in_bounds(su, sv)) continue;  // 2-D bounds check (method.md §2)
      const Eigen::Vector3f& Q = view(su, sv);
      if (!is_finite_value(Q.z())) continue;
      qx[n] = Q.x();
      qy[n] = Q.y();
      qz[n] = Q.z();
      ++n;
    }
  }
  // d = R Q + (t − p̄): the large translation cancels in double before the lanes see it.
  const Eigen::Vector3d offset = T.t - centre;
  Lane *dx = sample(0), *dy = sample(1), *dz = sample(2), *d2 = sample(3), *mask = sample(4);
  centre_samples(T.R.data(), offset.data(), n, qx, qy, qz, dx, dy, dz, d2);
  for (int k = 0; k < n; ++k)
    mask[k] = Lane(1);
  for (int k = n; k % kLanes != 0; ++k)
    dx[k] = dy[k] = dz[k] = d2[k] = mask[k] = Lane(0);
  n_ = (n + kLanes - 1) / kLanes * kLanes;
  return n;
}

namespace {

// One sample's gated weight and cost share (gated_cost of joint_pixel_kernel.hpp, branch-free).
template <typename Lane>
inline void gate_sample(Lane r, Lane d2, Lane mask, Lane gate, Lane n0, Lane& inside, Lane& w,
                        Lane& cost) {
  inside = mask * (std::abs(r) <= gate ? Lane(1) : Lane(0));
  const Lane e = inside > Lane(0) ? r : gate;
  const Lane we = fair_weight(e, d2, n0);
  cost = mask * we * e * e;
  w = inside * we;
}

// The SIMD loop of accumulate: √w (y, r) per sample into the columns, Σ cost and the count.
template <typename Lane, int kLanes>
JPCR_SIMD_CLONES void fill_columns(const QuadricScalars<Lane>& qs, const Lane* __restrict dx,
                                   const Lane* __restrict dy, const Lane* __restrict dz,
                                   const Lane* __restrict d2, const Lane* __restrict mask, int n,
                                   int stride, Lane gate, Lane n0, Lane* columns, double& cost,
                                   int& count) {
  const auto col = [columns, stride](int c) {
    return columns + static_cast<std::size_t>(c) * stride;
  };
  Lane* __restrict one = col(kOne), * __restrict j0 = col(kJ0), * __restrict j1 = col(kJ1), * __restrict j3 = col(kJ3), * __restrict j4 = col(kJ4), * __restrict j5 = col(kJ5), * __restrict res = col(kR), * __restrict gx = col(kGx), * __restrict gy = col(kGy), * __restrict m = col(kM);
  Lane cost_sum = 0, count_sum = 0;
#pragma omp simd simdlen(kLanes) reduction(+ : cost_sum, count_sum)
  for (int k = 0; k < n; ++k) {
    const SampleLinearization<Lane> l = linearize_sample(qs, dx[k], dy[k], dz[k]);
    Lane inside, w, c;
    gate_sample(l.r, d2[k], mask[k], gate, n0, inside, w, c);
    cost_sum += c;
    count_sum += inside;
    const Lane sw = std::sqrt(w);
    one[k] = sw;
    j0[k] = sw * l.J0;
    j1[k] = sw * l.J1;
    j3[k] = sw * l.J3;
    j4[k] = sw * l.J4;
    j5[k] = sw * l.J5;
    res[k] = sw * l.r;
    gx[k] = sw * l.gx;
    gy[k] = sw * l.gy;
    m[k] = sw * (l.vx * l.gy - l.vy * l.gx);  // (v × g)_z
  }
  cost = cost_sum;
  count = static_cast<int>(count_sum);
}

template <typename Lane, int kLanes>
JPCR_SIMD_CLONES void gated_costs(const QuadricScalars<Lane>& qs, const Lane* __restrict dx,
                                  const Lane* __restrict dy, const Lane* __restrict dz,
                                  const Lane* __restrict d2, const Lane* __restrict mask, int n,
                                  Lane gate, Lane n0, double& cost, int& count) {
  Lane cost_sum = 0, count_sum = 0;
#pragma omp simd simdlen(kLanes) reduction(+ : cost_sum, count_sum)
  for (int k = 0; k < n; ++k) {
    const SampleLinearization<Lane> l = linearize_sample(qs, dx[k], dy[k], dz[k]);
    Lane inside, w, c;
    gate_sample(l.r, d2[k], mask[k], gate, n0, inside, w, c);
    cost_sum += c;
    count_sum += inside;
  }
  cost = cost_sum;
  count = static_cast<int>(count_sum);
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

// Y = Σ √w(y, r) √w(y, r)ᵀ over the first `cols` columns: dot products along the samples (n is
// a multiple of kLanes), four at a time so that each load of column a serves four products.
template <typename Lane, int kLanes>
JPCR_SIMD_CLONES void column_products(const Lane* columns, int n, int stride, int cols, double* Y) {
  using Vec = typename LaneVector<Lane>::type;
  static_assert(sizeof(Vec) == kLanes * sizeof(Lane), "one register of lanes");
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

template <typename Lane>
void GatheredFrameTerms<Lane>::accumulate(const Quadricd& q, const SampleGate<double>& limits,
                                          bool with_pose, FrameTerms<double>& out) {
  const QuadricScalars<Lane> qs = QuadricScalars<Lane>::from(q.cast<Lane>());
  double cost = 0.0;
  int count = 0;
  fill_columns<Lane, kLanes>(qs, sample(0), sample(1), sample(2), sample(3), sample(4), n_,
                             capacity_, static_cast<Lane>(limits.gate),
                             static_cast<Lane>(limits.n0), column(0), cost, count);
  double Y[100];
  column_products<Lane, kLanes>(column(0), n_, capacity_, with_pose ? kColumns : kQuadricColumns,
                                Y);
  auto y = [&Y](int a, int b) { return Y[a * 10 + b]; };
  out.cost += cost;
  out.count += count;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j)
      out.C(i, j) += kGammaSign[i] * kGammaSign[j] * y(kGammaColumn[i], kGammaColumn[j]);
    out.g_gamma(i) += kGammaSign[i] * y(kGammaColumn[i], kR);
  }
  if (!with_pose) return;
  Matrix6d B_loc, A_loc;
  Vector6d g_loc;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      B_loc(i, j) = kLocalSign[i] * kGammaSign[j] * y(kLocalColumn[i], kGammaColumn[j]);
      A_loc(i, j) = kLocalSign[i] * kLocalSign[j] * y(kLocalColumn[i], kLocalColumn[j]);
    }
    g_loc(i) = kLocalSign[i] * y(kLocalColumn[i], kR);
  }
  // J_ξ = P J_loc with P = [[Rᵀ, 0], [[p̄]× Rᵀ, Rᵀ]] (header comment).
  Matrix6d P = Matrix6d::Zero();
  const Eigen::Matrix3d Rt = q.R.transpose();
  P.topLeftCorner<3, 3>() = Rt;
  P.bottomLeftCorner<3, 3>() = skew(q.center) * Rt;
  P.bottomRightCorner<3, 3>() = Rt;
  out.B.noalias() += P * B_loc;
  out.A.noalias() += P * A_loc * P.transpose();
  out.g_xi.noalias() += P * g_loc;
}

template <typename Lane>
double GatheredFrameTerms<Lane>::cost(const Quadricd& q, const SampleGate<double>& limits,
                                      int& count) {
  const QuadricScalars<Lane> qs = QuadricScalars<Lane>::from(q.cast<Lane>());
  double cost = 0.0;
  gated_costs<Lane, kLanes>(qs, sample(0), sample(1), sample(2), sample(3), sample(4), n_,
                            static_cast<Lane>(limits.gate), static_cast<Lane>(limits.n0), cost,
                            count);
  return cost;
}

template class GatheredFrameTerms<float>;
template class GatheredFrameTerms<double>;

}  // namespace jpcr
