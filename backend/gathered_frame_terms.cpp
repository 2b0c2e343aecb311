#include "jpcr/backend/gathered_frame_terms.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "jpcr/quadric/sample_columns.hpp"
#include "jpcr/quadric/simd_clones.hpp"

namespace jpcr {

namespace {

// J_loc = (g_x, g_y, −1, J₀, J₁, m) as (column, sign) (header comment).
constexpr int kLocalColumn[6] = {kColGx, kColGy, kColOne, kColJ0, kColJ1, kColM};
constexpr double kLocalSign[6] = {1, 1, -1, 1, 1, 1};

// R Q + o for a column-major R and the gathered point k, in double (inlined into the loops
// below, which stay branch-free so that they vectorise).
struct Moved {
  double x, y, z;
};
inline Moved moved(const double* R, const double* o, const float* qx, const float* qy,
                   const float* qz, int k) {
  const double x = qx[k], y = qy[k], z = qz[k];
  return {R[0] * x + R[3] * y + R[6] * z + o[0], R[1] * x + R[4] * y + R[7] * z + o[1],
          R[2] * x + R[5] * y + R[8] * z + o[2]};
}

// d = R Q + o and |d|² for the n gathered points, in double, stored as lanes. `omp simd`: without
// it GCC 12 left the x86-64-v3 clone scalar (the float → double loads), a quarter of a J-full
// iteration's time; vectorised, the results are the same to the bit.
template <typename Lane>
JPCR_SIMD_CLONES void centre_samples(const double* R, const double* o, int n, const float* qx,
                                     const float* qy, const float* qz, Lane* __restrict dx,
                                     Lane* __restrict dy, Lane* __restrict dz,
                                     Lane* __restrict d2) {
#pragma omp simd
  for (int k = 0; k < n; ++k) {
    const Moved e = moved(R, o, qx, qy, qz, k);
    dx[k] = static_cast<Lane>(e.x);
    dy[k] = static_cast<Lane>(e.y);
    dz[k] = static_cast<Lane>(e.z);
    d2[k] = static_cast<Lane>(e.x * e.x + e.y * e.y + e.z * e.z);
  }
}

// r_h² + d² of each of the n gathered points Q for the weight held at quadric w and pose (R, t)
// (frame_cost): X − p̄_w = R Q + o with o = t − p̄_w, r_h = gated r(X; w), d² = |X − p̄|² with
// X − p̄ = (X − p̄_w) + shift, shift = p̄_w − p̄. Branch-free, and `omp simd` as centre_samples.
template <typename Lane>
JPCR_SIMD_CLONES void held_weight_terms(const double* R, const double* o, const double* shift,
                                        const QuadricScalars<double>& w, double gate, int n,
                                        const float* qx, const float* qy, const float* qz,
                                        Lane* __restrict held) {
#pragma omp simd
  for (int k = 0; k < n; ++k) {
    const Moved e = moved(R, o, qx, qy, qz, k);                 // X − p̄_w
    const double vx = w.r00 * e.x + w.r01 * e.y + w.r02 * e.z;  // v = R_w (X − p̄_w)
    const double vy = w.r10 * e.x + w.r11 * e.y + w.r12 * e.z;
    const double vz = w.r20 * e.x + w.r21 * e.y + w.r22 * e.z + w.t_z;
    const double r = 0.5 * (w.a * vx * vx + 2.0 * w.b * vx * vy + w.c * vy * vy) - vz;
    const double r_h = r <= gate && r >= -gate ? r : gate;  // gated()
    const double fx = e.x + shift[0], fy = e.y + shift[1], fz = e.z + shift[2];
    held[k] = static_cast<Lane>(fx * fx + fy * fy + fz * fz + r_h * r_h);
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
    // point is written, the count advances only past samples).
    for (int k = 0; k < pattern_size; ++k) {
      const Eigen::Vector3f& Q = row[linear_[k]];
      qx[n] = Q.x();
      qy[n] = Q.y();
      qz[n] = Q.z();
      n += is_sample_point(Q) ? 1 : 0;
    }
  } else {
    for (int k = 0; k < pattern_size; ++k) {
      const int su = u + pattern[k].du, sv = v + pattern[k].dv;
      if (!view.in_bounds(su, sv)) continue;  // 2-D bounds check (method.md §2)
      const Eigen::Vector3f& Q = view(su, sv);
      if (!is_sample_point(Q)) continue;
      qx[n] = Q.x();
      qy[n] = Q.y();
      qz[n] = Q.z();
      ++n;
    }
  }
  // d = R Q + (t − p̄): the large translation cancels in double before the lanes see it.
  const Eigen::Vector3d offset = T.t - centre;
  ray_origin_ = -offset;
  Lane *dx = sample(0), *dy = sample(1), *dz = sample(2), *d2 = sample(3), *mask = sample(4);
  centre_samples(T.R.data(), offset.data(), n, qx, qy, qz, dx, dy, dz, d2);
  for (int k = 0; k < n; ++k)
    mask[k] = Lane(1);
  for (int k = n; k % kLanes != 0; ++k)
    dx[k] = dy[k] = dz[k] = d2[k] = mask[k] = Lane(0);
  n_ = (n + kLanes - 1) / kLanes * kLanes;
  gathered_ = n;
  return n;
}

template <typename Lane>
void GatheredFrameTerms<Lane>::accumulate(const Quadricd& q, const SampleGate<double>& limits,
                                          bool with_pose, double ray_min_cos2,
                                          FrameTerms<double>& out) {
  const QuadricScalars<Lane> qs = QuadricScalars<Lane>::from(q.cast<Lane>());
  const GatheredSamples<Lane> s{sample(0), sample(1), sample(2), sample(3), sample(4), n_};
  const Lane gate = static_cast<Lane>(limits.gate), n0 = static_cast<Lane>(limits.n0);
  // The ray of sample d is R (d + p̄ − o) in local axes (ray_foot_moment).
  const Eigen::Vector3d origin = q.R * ray_origin_;
  const RayFoot<Lane> foot{static_cast<Lane>(origin.x()), static_cast<Lane>(origin.y()),
                           static_cast<Lane>(origin.z()), static_cast<Lane>(ray_min_cos2)};
  const SampleCosts costs =
      with_pose
          ? fill_sample_columns<Lane, kPoseColumns>(qs, s, gate, n0, capacity_, column(0), foot)
          : fill_sample_columns<Lane, kQuadricColumns>(qs, s, gate, n0, capacity_, column(0));
  double Y[100];
  column_products<Lane>(column(0), n_, capacity_, with_pose ? kPoseColumns : kQuadricColumns, Y);
  auto y = [&Y](int a, int b) { return Y[a * 10 + b]; };
  out.cost += costs.gated;
  out.count += costs.count;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j)
      out.C(i, j) += kGammaSign[i] * kGammaSign[j] * y(kGammaColumn[i], kGammaColumn[j]);
    out.g_gamma(i) += kGammaSign[i] * y(kGammaColumn[i], kColR);
  }
  if (!with_pose) return;
  Matrix6d B_loc, A_loc;
  Vector6d g_loc;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      B_loc(i, j) = kLocalSign[i] * kGammaSign[j] * y(kLocalColumn[i], kGammaColumn[j]);
      A_loc(i, j) = kLocalSign[i] * kLocalSign[j] * y(kLocalColumn[i], kLocalColumn[j]);
    }
    g_loc(i) = kLocalSign[i] * y(kLocalColumn[i], kColR);
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
  const SampleCosts costs =
      sample_costs<Lane>(qs, {sample(0), sample(1), sample(2), sample(3), sample(4), n_},
                         static_cast<Lane>(limits.gate), static_cast<Lane>(limits.n0));
  count = costs.count;
  return costs.gated;
}

template <typename Lane>
double GatheredFrameTerms<Lane>::held_cost(const Quadricd& q, const Quadricd& q_weight,
                                           const RigidMotion<double>& T_weight,
                                           const SampleGate<double>& limits, int& count) {
  // Each sample's r_h² + d² at (q_weight, T_weight) replaces its d² (frame_cost).
  const float *qx = raw_.data(), *qy = qx + capacity_, *qz = qy + capacity_;
  Lane* held = sample(3);
  const Eigen::Vector3d offset = T_weight.t - q_weight.center, shift = q_weight.center - q.center;
  held_weight_terms(T_weight.R.data(), offset.data(), shift.data(),
                    QuadricScalars<double>::from(q_weight), limits.gate, gathered_, qx, qy, qz,
                    held);
  const QuadricScalars<Lane> qs = QuadricScalars<Lane>::from(q.cast<Lane>());
  const SampleCosts costs =
      held_sample_costs<Lane>(qs, {sample(0), sample(1), sample(2), held, sample(4), n_},
                              static_cast<Lane>(limits.gate), static_cast<Lane>(limits.n0));
  count = costs.count;
  return costs.gated;
}

template class GatheredFrameTerms<float>;
template class GatheredFrameTerms<double>;

}  // namespace jpcr
