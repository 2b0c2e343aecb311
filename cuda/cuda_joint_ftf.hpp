// J-ftf on the GPU (method.md §6; issue 7): the joint refinement of one pose T₂ and the dense
// quadrics of frame 1, with the same per-pixel code as the CPU reference
// (backend/joint_pixel_kernel.hpp: linearize_joint_pixel<Scalar, 2>, add_schur_terms,
// linearized_pixel_cost) and the same Levenberg-Marquardt loop (backend/joint_problem.hpp).
//
//   CudaJointSystem        JointProblem on the device: one thread per reference pixel builds
//                          C_p, B_p, b_p, factors C_p (Cholesky, per thread), keeps k and K for
//                          the back-substitution and reduces the 6x6 Schur system S, s (plus
//                          diag A, cost, counts) in double per block, then over the blocks.
//                          The step kernel back-substitutes Δγ_p = k − K Δξ and re-associates at
//                          the candidate pose for its cost. The 6x6 solve runs on the host.
//   CudaJointFrameToFrame  the Refiner ("j-ftf") over it; make_refiner(name, params, device)
//                          in refiner_factory.hpp picks it for `device: cuda`.
//
// The quadrics stay on the device during a refinement (a candidate buffer is swapped in when a
// step is accepted); device buffers grow to the largest frame seen and are reused by every later
// iteration and pair (no per-iteration cudaMalloc). Plain C++ header; the CUDA side is in
// cuda_joint_ftf.cu.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#include "jpcr/backend/joint_problem.hpp"
#include "jpcr/backend/refiner.hpp"
#include "jpcr/cuda/cuda_quadric_fit.hpp"

namespace jpcr {

/// Device times (CUDA events) of the last linearize() and propose(), in ms: kernels and the
/// download of the reduced sums, without the host's 6x6 work.
struct CudaJointTiming {
  float linearize_ms = 0;
  float propose_ms = 0;
};

class CudaJointSystem final : public JointProblem {
 public:
  /// Throws CudaError when no CUDA device is usable, std::invalid_argument for Q-full terms
  /// (estimate_quadrics = false: only J-ftf runs on the GPU).
  explicit CudaJointSystem(const JointTermParams& params,
                           CudaPrecision precision = CudaPrecision::kDouble);
  ~CudaJointSystem() override;
  CudaJointSystem(const CudaJointSystem&) = delete;
  CudaJointSystem& operator=(const CudaJointSystem&) = delete;

  /// Uploads a pair (frames[0] the reference, both of the camera's size; checked by the
  /// caller) and its initial state {I, T₂} with one quadric per reference pixel.
  void load(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
            const NeighbourhoodPattern& pattern, JointState initial);
  /// The same from the poses {I, T₂} and Quad IT's map, converted into the state kept from the
  /// last pair (fill_joint_state: no fresh host pages when the size is unchanged), less the
  /// `edges` (edge_quadrics, joint_problem.hpp; empty: none). Returns how many it left out.
  int load(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
           const NeighbourhoodPattern& pattern, const std::vector<Eigen::Isometry3d>& poses,
           const QuadricMap& initial, const std::vector<unsigned char>& edges = {});

  ReducedSystem linearize(double lambda) override;  // factors stay on the device (empty here)
  double propose(const ReducedSystem& system, double lambda,
                 const std::vector<Vector6d>& pose_steps) override;
  void accept() override;
  const JointState& state() override;  // downloads the quadrics when they changed

  /// For the parity tests: the candidate of the last propose() and the back-substitution
  /// factors of the last linearize() (active pixels, row-major order), downloaded.
  JointState candidate();
  std::vector<PairFactors> factors();

  CudaPrecision precision() const { return precision_; }
  CudaJointTiming last_timing() const { return timing_; }
  /// cudaMalloc calls so far (only for the first pair of each larger size).
  std::size_t device_allocations() const;
  /// A check for tests: fill every device output with 0xFF bytes (NaN) before each kernel.
  void set_poison_outputs(bool on) { poison_ = on; }

 private:
  struct Device;
  template <typename Scalar>
  void launch_linearize(double lambda);
  template <typename Scalar>
  void launch_step(const Vector6d& pose_step);
  void upload(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
              const NeighbourhoodPattern& pattern);  // the frames, pattern and state_ (checked)
  void copy_to_device(const std::vector<VertexMap>& frames, const CameraIntrinsics& camera,
                      const NeighbourhoodPattern& pattern);  // upload's work

  JointTermParams params_;
  CudaPrecision precision_;
  std::unique_ptr<Device> device_;
  JointState state_;  // poses and valid on the host; quadrics when fresh
  bool host_quadrics_fresh_ = false;
  // What the device buffers hold: the factors of a linearize() of the current state, and a
  // candidate of a propose() from them (propose, accept and candidate check these).
  bool linearized_ = false, proposed_ = false;
  std::vector<Eigen::Isometry3d> candidate_poses_;
  CudaJointTiming timing_;
  bool poison_ = false;
};

class CudaJointFrameToFrame final : public Refiner {
 public:
  /// Throws CudaError when no CUDA device is usable (check cuda_device_available() first).
  explicit CudaJointFrameToFrame(const JointParams& params = {},
                                 CudaPrecision precision = CudaPrecision::kDouble);
  ~CudaJointFrameToFrame() override;
  using Refiner::refine;
  /// Exactly two frames; initial_poses = {I, T₂}. Throws std::invalid_argument otherwise.
  /// Thread-safe (calls are serialised: they share the device buffers).
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override;
  std::string name() const override { return "j-ftf"; }
  const JointParams& params() const override { return params_; }
  CudaPrecision precision() const { return system_->precision(); }
  std::size_t device_allocations() const;

 private:
  JointParams params_;
  std::unique_ptr<CudaJointSystem> system_;
  mutable std::mutex mutex_;
};

}  // namespace jpcr
