// One quadric's terms in one frame, the CPU way (the same sums as accumulate_frame_terms and
// frame_cost of joint_pixel_kernel.hpp, which the GPU runs per sample): the neighbourhood is
// gathered once into contiguous arrays centred on p̄, then one SIMD loop linearises every sample
// and the sums are a single small matrix product.
//
// The sums need only ten numbers per sample. With v = R (X − p̄), g = (g_x, g_y, −1) and
// m = v_x g_y − v_y g_x (quadric_model.hpp), the pose Jacobian of method.md §6 factors as
//
//     J_ξ = [g_w; X × g_w] = P J_loc,   J_loc = [g; v × g] = [g_x, g_y, −1, J₀, J₁, m],
//     P = [[Rᵀ, 0], [[p̄]× Rᵀ, Rᵀ]]      (g_w = Rᵀ g, X = p̄ + Rᵀ v),
//
// since v × g = (J₀, J₁, m) with J₀, J₁ the first two entries of J_γ. So J_γ and J_loc are
// entries of y = (1, J₀, J₁, J₃, J₄, J₅, g_x, g_y, m) up to sign, and with the residual r the
// normal equations of the frame are read off the 10x10 matrix Y = Σ w (y, r)(y, r)ᵀ, then
// B = P B_loc, A = P A_loc Pᵀ, g_ξ = P g_loc in double. The centred local coordinates keep the
// float lanes well scaled; everything per pixel is double.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "jpcr/backend/joint_pixel_kernel.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr {

/// Thread-local buffers and the gathered sums of one frame. Lane is the SIMD type of the
/// per-sample work (float: twice the lanes of double; tests compare both with the reference).
template <typename Lane>
class GatheredFrameTerms {
 public:
  static constexpr int kLanes = 32 / sizeof(Lane);  // one AVX register
  static constexpr int kColumns = 10;               // y (9) and r (sample_columns.hpp)

  explicit GatheredFrameTerms(int pattern_size)
      : capacity_((pattern_size + kLanes - 1) / kLanes * kLanes),
        raw_(static_cast<std::size_t>(capacity_) * 3),
        samples_(static_cast<std::size_t>(capacity_) * 5),
        columns_(static_cast<std::size_t>(capacity_) * kColumns) {}

  /// Gathers the samples of `pattern` around (u, v) of `view`, mapped into frame 1 by T, as
  /// d = T Q − p̄ (method.md §2 bounds check, invalid depth skipped). Returns their number.
  int gather(const VertexView& view, const RigidMotion<double>& T, const PixelOffset* pattern,
             int pattern_size, int u, int v, const Eigen::Vector3d& centre);

  /// The frame's FrameTerms (with_pose: also B, A, g_ξ, with the lever arms at the rays' foot
  /// points unless ray_min_cos2 is kNoRayFoot) at quadric q for the gathered samples.
  void accumulate(const Quadricd& q, const SampleGate<double>& limits, bool with_pose,
                  double ray_min_cos2, FrameTerms<double>& out);

  /// Σ w r² (gated samples at w(g) g²) and the count inside the gate, for the gathered samples.
  double cost(const Quadricd& q, const SampleGate<double>& limits, int& count);

  /// The same cost with every sample's weight held at quadric q_weight and pose T_weight
  /// (frame_cost's held weights): the gathered samples' residuals stay at the gather's T.
  double held_cost(const Quadricd& q, const Quadricd& q_weight, const RigidMotion<double>& T_weight,
                   const SampleGate<double>& limits, int& count);

 private:
  Lane* sample(int i) { return samples_.data() + static_cast<std::size_t>(i) * capacity_; }
  Lane* column(int i) { return columns_.data() + static_cast<std::size_t>(i) * capacity_; }

  int capacity_ = 0;
  const PixelOffset* pattern_ = nullptr;                  // the pattern reach_ and linear_ describe
  int pattern_width_ = 0;                                 // at this image width
  int reach_ = 0;                                         // max |du|, |dv|
  std::vector<std::ptrdiff_t> linear_;                    // dv · width + du per offset
  Eigen::Vector3d ray_origin_ = Eigen::Vector3d::Zero();  // p̄ − T.t: camera centre to p̄
  int n_ = 0;                  // gathered samples, padded to a multiple of kLanes with mask 0
  int gathered_ = 0;           // gathered samples, unpadded
  std::vector<float> raw_;     // the gathered points Q (x, y, z arrays)
  std::vector<Lane> samples_;  // dx dy dz d² mask
  std::vector<Lane> columns_;  // √w (y, r), column-major n x 10
};

/// The per-frame sums for linearize_joint_pixel / linearized_pixel_cost on the CPU (the sampler
/// interface of joint_pixel_kernel.hpp), backed by one GatheredFrameTerms per thread.
template <typename Lane>
class GatheredSampler {
 public:
  explicit GatheredSampler(int pattern_size) : terms_(pattern_size) {}

  void accumulate(const Quadricd& q, const VertexView& view, const RigidMotion<double>& T,
                  bool with_pose, double ray_min_cos2, const PixelOffset* pattern, int pattern_size,
                  int u, int v, const SampleGate<double>& limits, FrameTerms<double>& out) {
    terms_.gather(view, T, pattern, pattern_size, u, v, q.center);
    terms_.accumulate(q, limits, with_pose, ray_min_cos2, out);
  }
  double cost(const Quadricd& q, const Quadricd& q_weight, const VertexView& view,
              const RigidMotion<double>& T, const RigidMotion<double>& T_weight,
              const PixelOffset* pattern, int pattern_size, int u, int v,
              const SampleGate<double>& limits, int& count) {
    terms_.gather(view, T, pattern, pattern_size, u, v, q.center);
    if (&q == &q_weight && T_weight.R == T.R && T_weight.t == T.t)
      return terms_.cost(q, limits, count);
    return terms_.held_cost(q, q_weight, T_weight, limits, count);
  }

 private:
  GatheredFrameTerms<Lane> terms_;
};

extern template class GatheredFrameTerms<float>;
extern template class GatheredFrameTerms<double>;

}  // namespace jpcr
