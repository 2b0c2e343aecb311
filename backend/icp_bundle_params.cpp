#include "jpcr/backend/icp_bundle_params.hpp"

#include "jpcr/quadric/error.hpp"

namespace jpcr {

void IcpBundleParams::validate() const {
  // Both are pixel distances in images at most 16384 px wide (CameraIntrinsics::validate); the
  // bound also keeps their products with the width inside int.
  if (grid_stride < 1 || grid_stride > 16384)
    throw InputError("grid_stride: must be in [1, 16384] (px)");
  if (normal_offset < 1 || normal_offset > 16384)
    throw InputError("normal_offset: must be in [1, 16384] (px)");
  if (!(normal_max_jump > 0.0f)) throw InputError("normal_max_jump: must be > 0");
  if (!(min_overlap > 0.0 && min_overlap <= 1.0))
    throw InputError("min_overlap: must be in (0, 1]");
  if (!(max_distance > 0.0)) throw InputError("max_distance: must be > 0 (m)");
  if (!(max_normal_angle > 0.0 && max_normal_angle <= 180.0))
    throw InputError("max_normal_angle: must be in (0, 180] (deg)");
  if (min_pair_terms < 1) throw InputError("min_pair_terms: must be at least 1");
  if (!(robust_scale > 0.0)) throw InputError("robust_scale: must be > 0 (m)");
  if (outer_iterations < 1 || outer_iterations > 100)
    throw InputError("outer_iterations: must be in [1, 100]");
  if (solver_iterations < 1 || solver_iterations > 1000)
    throw InputError("solver_iterations: must be in [1, 1000]");
  if (!(translation_tolerance > 0.0)) throw InputError("translation_tolerance: must be > 0 (m)");
  if (!(rotation_tolerance > 0.0)) throw InputError("rotation_tolerance: must be > 0 (rad)");
  if (!(degeneracy_threshold >= 0.0 && degeneracy_threshold < 1.0))
    throw InputError("degeneracy_threshold: must be in [0, 1)");
  if (threads < 0) throw InputError("threads: must be >= 0 (0: one per core)");
}

const char* to_string(BundleLoss loss) {
  return loss == BundleLoss::huber ? "huber" : "cauchy";
}

BundleLoss parse_bundle_loss(const std::string& name) {
  if (name == "huber") return BundleLoss::huber;
  if (name == "cauchy") return BundleLoss::cauchy;
  throw InputError("robust_loss: '" + name + "' is not one of huber, cauchy");
}

}  // namespace jpcr
