// J-ftf (method.md §6): joint refinement of one pose T = T₂ (frame 2 → frame 1) and the dense
// quadrics of frame 1. Mathematically J-full with M = 2; it runs the same loop (refine_window)
// with the per-pixel kernel instantiated for two frames (JointPixelSystem<·, 2>, the form the
// CUDA J-ftf runs). Like J-full it keeps each quadric's blocks and damped factor (84 numbers,
// joint_system.hpp QuadricBlocks) from the linearisation instead of rebuilding its system for the
// step (with factors only: 0.76 s instead of 1.26 s of CPU per iteration at 320x240 on one
// thread), and after a rejected step only re-damps them (JointSystem::redamp) instead of
// linearising again.
#pragma once

#include "jpcr/backend/refiner.hpp"

namespace jpcr {

class JointFrameToFrame final : public Refiner {
 public:
  explicit JointFrameToFrame(const JointParams& params = {});
  using Refiner::refine;
  /// Exactly two frames; initial_poses = {I, T₂}. Throws std::invalid_argument otherwise.
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override;
  std::string name() const override { return "j-ftf"; }
  const JointParams& params() const override { return params_; }

 private:
  JointParams params_;
};

}  // namespace jpcr
