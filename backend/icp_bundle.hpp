// ICP-bundle (method.md §9), the strongest classical baseline: dense point-to-plane residuals
// between every overlapping pair (i, j) of a window of M frames, all poses T_2 … T_M solved
// jointly with Ceres, T_1 = I held fixed (the gauge). Each solve runs Levenberg-Marquardt with a
// robust loss on poses on PoseManifold (point_to_plane_cost.hpp); the correspondences are
// re-found at the new poses before the next solve (the outer loop). Built only with Ceres.
//
//   IcpBundle bundle(params);
//   RefinementResult r = bundle.refine(frames, initial_poses);  // frames[0] is the reference
//
// A frame that overlaps no frame connected to the reference (overlap test by projection at the
// initial poses), or that the last association finds tied to it by no pair with min_pair_terms
// correspondences (a solve took it where nothing pairs with it), is reported in report.isolated
// with the verdict no_overlap, and its pose is returned as given; the connected frames are still
// refined. A window whose last solve does
// not observe every solved pose (report.degeneracy below params.degeneracy_threshold: one
// plane) is `degenerate`. ICP-bundle estimates no quadrics (RefinementResult::quadrics is
// empty) and no covariance (zero blocks); refines_quadrics() is false.
#pragma once

#include "jpcr/backend/icp_bundle_params.hpp"
#include "jpcr/backend/refiner.hpp"

namespace jpcr {

class IcpBundle final : public Refiner {
 public:
  explicit IcpBundle(const IcpBundleParams& params = {});

  /// From depth frames: vertex maps only (no Quad IT, which ICP-bundle does not use).
  RefinementResult refine(const std::vector<Frame>& frames,
                          const std::vector<Eigen::Isometry3d>& initial_poses) const override;
  /// `initial_quadrics` is ignored.
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override;
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses) const;

  std::string name() const override { return "icp-bundle"; }
  bool refines_quadrics() const override { return false; }
  /// The interface's joint parameters (their Quad IT part is what a caller would run on the
  /// reference); ICP-bundle uses none of them.
  const JointParams& params() const override { return joint_; }
  const IcpBundleParams& bundle_params() const { return params_; }

 private:
  IcpBundleParams params_;
  JointParams joint_;
};

}  // namespace jpcr
