#include "jpcr/backend/joint_params.hpp"

#include "jpcr/quadric/error.hpp"

namespace jpcr {

void JointParams::validate() const {
  quadric.validate();
  if (max_iterations < 1 || max_iterations > 1000)
    throw InputError("max_iterations: must be in [1, 1000]");
  if (!(translation_tolerance > 0.0)) throw InputError("translation_tolerance: must be > 0 (m)");
  if (!(rotation_tolerance > 0.0)) throw InputError("rotation_tolerance: must be > 0 (rad)");
  if (!(occlusion_threshold > 0.0f)) throw InputError("occlusion_threshold: must be > 0 (m)");
  if (!(occlusion_fraction >= 0.0f)) throw InputError("occlusion_fraction: must be >= 0");
  if (min_frame_terms < 1) throw InputError("min_frame_terms: must be at least 1");
  if (!(min_pivot_ratio > 0.0 && min_pivot_ratio < 1.0))
    throw InputError("min_pivot_ratio: must be in (0, 1)");
  if (!(ray_min_cosine >= 0.0f && ray_min_cosine < 1.0f))
    throw InputError("ray_min_cosine: must be in [0, 1) (0: lever arms at the samples)");
  // Below 0.1° a quadrant's plane can differ from its window's by rounding alone (a plane).
  if (!(edge_tilt == 0.0f || (edge_tilt >= 0.1f && edge_tilt <= 90.0f)))
    throw InputError("edge_tilt: must be 0 (every quadric takes part) or in [0.1, 90] (deg)");
  if (!(initial_damping > 0.0)) throw InputError("initial_damping: must be > 0");
  if (!(damping_factor > 1.0)) throw InputError("damping_factor: must be > 1");
  if (!(damping_decrease > 1.0)) throw InputError("damping_decrease: must be > 1");
  if (!(max_damping > initial_damping))
    throw InputError("max_damping: must exceed initial_damping");
  if (min_active_quadrics < 1) throw InputError("min_active_quadrics: must be at least 1");
  // At most 1 PiB: a byte count that fits std::size_t.
  if (!(block_memory_mb >= 0.0 && block_memory_mb <= 1.0e9))
    throw InputError("block_memory_mb: must be in [0, 1e9] (MiB; 0 keeps no blocks)");
  if (!(degeneracy_threshold >= 0.0 && degeneracy_threshold < 1.0))
    throw InputError("degeneracy_threshold: must be in [0, 1)");
}

}  // namespace jpcr
