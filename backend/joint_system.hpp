// The CPU driver of the joint normal equations (method.md §6–§8): loops the per-pixel kernels of
// joint_pixel_kernel.hpp over the reference frame in parallel, reduces the reduced system
// (S, s) in double, solves it for the poses and back-substitutes the quadrics. The
// Levenberg-Marquardt loop around it is in joint_window.cpp.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "jpcr/backend/joint_pixel_kernel.hpp"
#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/se3.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

/// The unknowns of a window: T_1 … T_M (T_1 = I, the gauge) and one quadric per pixel of the
/// reference frame (row-major), where Quad IT gave one.
struct JointState {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Quadricd> quadrics;
  std::vector<unsigned char> valid;  // 1 where the pixel has a quadric
};

/// Q-full: an active quadric and the frames that see it (bit j − 1 for frame j).
struct FixedPixel {
  std::size_t pixel = 0;  // row-major index in the reference frame
  unsigned seen = 0;
  bool operator<(const FixedPixel& o) const { return pixel < o.pixel; }
  bool operator==(const FixedPixel& o) const { return pixel == o.pixel && seen == o.seen; }
};

/// What the back-substitution of J-ftf needs of one active quadric for one damping:
/// Δγ_p = k − K Δξ (42 numbers; the GPU J-ftf keeps these, CudaJointSystem::factors).
struct PairFactors {
  std::size_t pixel = 0;    // row-major index in the reference frame
  QuadricVector<double> k;  // C_p⁻¹ b_p
  Matrix6d K;               // C_p⁻¹ B_pᵀ
};

/// What the CPU keeps of one active quadric's linearisation (48 numbers, and its B_jp in
/// ReducedSystem::couplings): the undamped C_p and −b_p, from which another damping λ needs no
/// new sums (JointSystem::redamp), and the Cholesky factor of C_p + λ diag C_p at the system's
/// damping, for the back-substitution Δγ_p = (C_p + λ diag C_p)⁻¹ (b_p − Σ_j B_jpᵀ Δξ_j).
struct QuadricBlocks {
  std::size_t pixel = 0;          // row-major index in the reference frame
  unsigned seen = 0;              // bit j − 2: frame j sees it (B_jp is zero otherwise)
  std::array<double, 21> C;       // the lower triangle of the undamped C_p, column by column
  std::array<double, 21> L;       // the lower triangle of the damped C_p's Cholesky factor
  QuadricVector<double> g_gamma;  // −b_p
};

/// S = A − Σ_p B_p C_p⁻¹ B_pᵀ and s = a − Σ_p B_p C_p⁻¹ b_p (n = 6 (M − 1)), with the damping λ
/// already in C_p but not in A (solve_poses adds λ diag A).
struct ReducedSystem {
  Eigen::MatrixXd S;
  Eigen::VectorXd s;
  Eigen::VectorXd A_diagonal;
  double cost = 0.0;                     // Σ w r² over the active quadrics
  long terms = 0;                        // their terms inside the gate
  int active = 0;                        // quadrics taking part
  std::vector<int> seen;                 // per pose T_2 … T_M: active quadrics that frame sees
  std::vector<FixedPixel> fixed_active;  // Q-full: the active quadrics and their frames
  double damping = 0.0;                  // λ in the C_p of S (and of the blocks' factors)
  // Where the blocks fit in JointSystem's budget: every active quadric's blocks, its B_jp
  // (couplings[k (M − 1) + j − 2] for blocks[k]), and S and s before any quadric is eliminated
  // (Σ_p A_p and a = −Σ_p g_ξp): what redamp and the step without new sums need.
  bool keeps_blocks = false;
  std::vector<QuadricBlocks> blocks;
  std::vector<Matrix6d> couplings;
  Eigen::MatrixXd A_sum;
  Eigen::VectorXd a_sum;
};

/// A proposed step and where it leads.
struct JointStep {
  std::vector<Vector6d> pose_steps;                  // Δξ of T_2 … T_M
  std::vector<QuadricVector<double>> quadric_steps;  // Δγ_p per pixel, 0 where inactive
  JointState candidate;                              // exp(Δξ^) T, γ ⊕ Δγ
  double cost = 0.0;  // at the candidate, over the terms of the linearisation (its active
                      // quadrics and the frames that saw each): linearized_pixel_cost
};

/// How the CPU evaluates each quadric's per-frame sums: gathered into contiguous arrays and
/// vectorised across samples in float lanes (gathered_frame_terms.hpp; the default), the same in
/// double lanes (the gathered sums without float rounding, for tests), or sample by sample in
/// double exactly as the GPU kernels do (the reference the tests compare with).
enum class JointSampling { kGathered, kGatheredDouble, kReference };

/// The memory a JointSystem may give its kept blocks unless told otherwise (JointParams'
/// block_memory_mb): 1 GiB holds a 640x480 window of up to 8 frames.
inline constexpr std::size_t kDefaultBlockMemory = std::size_t{1} << 30;

class JointSystem {
 public:
  /// frames[0] is the reference; all frames share `camera` (sizes are checked by the caller).
  /// Throws std::invalid_argument unless 2 ≤ frames.size() ≤ kMaxWindowFrames.
  /// The linearisation keeps every active quadric's blocks (QuadricBlocks, couplings) where
  /// those of all valid quadrics fit in `block_memory` bytes (block_bytes each): the step then
  /// back-substitutes from them and a new damping needs no new sums (redamp). Otherwise each
  /// quadric's system is computed again for the step, and every damping linearises again.
  JointSystem(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
              const NeighbourhoodPattern& pattern, const JointTermParams& params,
              JointSampling sampling = JointSampling::kGathered,
              std::size_t block_memory = kDefaultBlockMemory);

  int frames() const { return static_cast<int>(views_.size()); }
  /// The bytes one quadric's kept blocks take in a window of `frames` frames (at 640x480 a pair
  /// keeps about 210 MB, a window of 5 about 480 MB).
  static std::size_t block_bytes(int frames);
  const JointTermParams& params() const { return params_; }

  /// The reduced system at `state`, with the Levenberg damping λ on C_p.
  ReducedSystem linearize(const JointState& state, double lambda) const;
  /// The same into `out`, reusing its buffers: a refinement loop keeps one ReducedSystem, as
  /// J-ftf's blocks at 640x480 are about 200 MB, on fresh pages each iteration otherwise.
  void linearize(const JointState& state, double lambda, ReducedSystem& out) const;

  /// Turns `system`, a linearize(state, λ₀) of this JointSystem, into linearize(state, λ) (to
  /// rounding) without new sums: the damping is all that changes after a rejected step. J-ftf and
  /// J-full eliminate their kept blocks again (no gathering); Q-full's system does not depend on
  /// λ. False, and `system` unchanged, where it cannot (the blocks were over the budget, or
  /// `system` is of another size): then linearize again. After an exception (a worker out of
  /// memory) `system` is to be linearised again; a step on it throws until then.
  bool redamp(double lambda, ReducedSystem& system) const;

  /// Solves (S + λ diag A) Δξ = s with LDLT; false when it is not positive definite or the step
  /// is not finite.
  static bool solve_poses(const ReducedSystem& system, double lambda,
                          std::vector<Vector6d>& pose_steps);

  /// Back-substitutes Δγ_p for the poses' step and evaluates the cost of the candidate over the
  /// linearisation's terms (each frame's pattern where it was associated at `state`). `system` and
  /// λ are those of linearize(state, λ) (or redamp): the blocks kept in `system`, else each
  /// quadric's system computed again. Throws std::invalid_argument when the blocks are kept and
  /// λ is not the system's damping.
  JointStep step(const JointState& state, const ReducedSystem& system, double lambda,
                 const std::vector<Vector6d>& pose_steps) const;
  /// The same into `out`, reusing its buffers (the candidate state and the quadric steps).
  void step(const JointState& state, const ReducedSystem& system, double lambda,
            const std::vector<Vector6d>& pose_steps, JointStep& out) const;

 private:
  /// The window seen from `motions` (one per frame, T_j as RigidMotion).
  JointWindowView<double> window_view(const std::vector<RigidMotion<double>>& motions) const;
  // Each costs the candidate: `window` at the linearisation's poses, `next` at the candidate's.
  void step_kept(const JointState& state, const ReducedSystem& system, double lambda,
                 const JointWindowView<double>& window, const JointWindowView<double>& next,
                 JointStep& out) const;
  void step_fixed(const JointState& state, const ReducedSystem& system,
                  const JointWindowView<double>& window, const JointWindowView<double>& next,
                  JointStep& out) const;
  void step_window(const JointState& state, double lambda, const JointWindowView<double>& window,
                   const JointWindowView<double>& next, JointStep& out) const;
  void start_step(const JointState& state, const std::vector<Vector6d>& pose_steps,
                  JointStep& out) const;

  std::vector<VertexView> views_;
  PinholeProjection camera_;
  std::vector<PixelOffset> pattern_;
  JointTermParams params_;
  JointSampling sampling_ = JointSampling::kGathered;
  std::size_t block_memory_ = kDefaultBlockMemory;
  int width_ = 0, height_ = 0;
};

/// Per pixel, the samples of `reference` inside the gate of its quadric in `state` (0 where the
/// pixel has none): a refined quadric that no longer fits min_samples of its own samples has
/// left the surface (the gate made the move cost-free) and is not a curvature estimate.
std::vector<int> reference_inliers(const VertexMap& reference, const NeighbourhoodPattern& pattern,
                                   const JointTermParams& params, const JointState& state);

}  // namespace jpcr
