// Q-full (method.md §8): the poses T_2 … T_M of a window aligned to the quadrics of the reference
// frame, which stay fixed (Quad IT). No residual couples two poses, so each pose is an
// independent 6x6 problem: each runs the loop of J-full (refine_window) alone, without the
// quadric unknowns, with its own damping, step test and verdict (RefinementReport::
// pose_verdicts), and the result puts them side by side (block-diagonal covariance).
#pragma once

#include "jpcr/backend/refiner.hpp"

namespace jpcr {

class FixedQuadricAlignment final : public Refiner {
 public:
  explicit FixedQuadricAlignment(const JointParams& params = {});
  using Refiner::refine;
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override;
  std::string name() const override { return "q-full"; }
  const JointParams& params() const override { return params_; }
  bool refines_quadrics() const override { return false; }

 private:
  JointParams params_;
};

}  // namespace jpcr
