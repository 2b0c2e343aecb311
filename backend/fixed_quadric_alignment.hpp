// Q-full (method.md §8): the poses T_2 … T_M of a window aligned to the quadrics of the reference
// frame, which stay fixed (Quad IT). No residual couples two poses, so the reduced system is
// block-diagonal and each pose is an independent 6x6 problem; it runs the loop of J-full
// (refine_window) without the quadric unknowns.
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
