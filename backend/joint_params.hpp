// Tunables of the joint refiners J-ftf, J-full and Q-full (method.md §6–§8). A flat struct with
// in-class defaults and units; YAML maps onto it in io/ only.
#pragma once

#include <cstddef>

#include "jpcr/backend/joint_pixel_kernel.hpp"
#include "jpcr/quadric/quadric_params.hpp"

namespace jpcr {

/// The largest window J-full accepts (M, the reference frame included).
inline constexpr int kMaxWindowFrames = 16;

struct JointParams {
  // The pattern, the initial normals and Quad IT (the initial quadrics); quadric.fit's weight n₀,
  // gate and min_samples also apply to every joint term.
  QuadricParams quadric;

  int max_iterations = 20;              // accepted Levenberg-Marquardt steps at most
  double translation_tolerance = 1e-5;  // m: converged when every pose step moves less ...
  double rotation_tolerance = 1e-5;     // rad: ... and turns less than this
  float occlusion_threshold = 0.03f;    // m: association rejected when image j's depth at the
  float occlusion_fraction = 0.02f;     //    projected centre differs from c_z by more than
                                        //    threshold + fraction · c_z (fraction of depth)
  int min_frame_terms = 10;             // terms a frame j needs for its association to count
  double min_pivot_ratio = 1e-2;        // C_p ill-conditioned below it (joint_pixel_kernel.hpp)
  // > 0: the other frames' terms take their lever arms at the foot point of each sample's ray,
  // unless the ray meets the quadric at a cosine below this (accumulate_frame_terms; 0.2 is the
  // measured setting). 0 (the default, the paper's Jacobians): at the samples. Off by default
  // until it is measured on every scene and noise level: it removes most of J-ftf's bias under
  // range noise on some pairs and not on others (accumulate_frame_terms).
  float ray_min_cosine = 0.0f;
  // deg: a quadric whose initial normal came from a quadrant of its window tilted more than
  // this from the window's plane (estimate_normals' quadrant_tilt: the window straddles a crease
  // or a depth step) stays out of the joint system and keeps its Quad IT fit (edge_quadrics,
  // joint_problem.hpp, from the reference's vertices and quadric.normals, as Quad IT's initial
  // map is made). 0: every valid quadric takes part; else in [0.1, 90].
  float edge_tilt = 2.0f;
  // After the loop (once it has taken a step), each quadric keeps its refined fit only where that
  // fit's gated cost over the window's samples is not above its Quad IT start's at the refined
  // poses (keep_lower_cost_fits, lower_cost_fit.hpp: Quad IT's step test, per quadric); the poses
  // do not change. false: every refined fit, as the paper.
  bool keep_lower_cost_fit = true;
  double initial_damping = 1e-4;  // λ: relative Levenberg damping of diag A and diag C_p
  double damping_factor = 10.0;   // λ ← λ·f after a rejected step ...
  double damping_decrease = 3.0;  // ... and λ ← λ/d after an accepted one (d < f: λ settles
                                  // near the smallest damping that works instead of bouncing
                                  // between two values with every other step rejected)
  double max_damping = 1e6;       // λ above it: the cost cannot be lowered → diverged
  int min_active_quadrics = 50;   // fewer quadrics seen in another frame: too_few_quadrics
  // MiB: each linearisation keeps every quadric's blocks (JointSystem::block_bytes: 0.7 kB in
  // a pair, 1.6 kB in a window of 5) where they fit in this, so that the step back-substitutes
  // without computing each quadric's system again and a rejected step costs only a new damping
  // (JointSystem::redamp); otherwise both compute the sums again (the same results, slower).
  // 1024 holds a 640x480 window of 8 frames; 0 never keeps them.
  double block_memory_mb = 1024.0;
  // Unit-free λmin / λmax of S below it: degenerate. Measured at 160x120: 0.007-0.02 on the
  // synthetic scenes (J-ftf, J-full windows of 4), 5e-10 on the corridor (two parallel planes).
  double degeneracy_threshold = 1e-4;

  /// The per-pixel part, as the kernels receive it.
  JointTermParams terms(bool estimate_quadrics) const {
    JointTermParams t;
    t.fit = quadric.fit;
    t.occlusion_threshold = occlusion_threshold;
    t.occlusion_fraction = occlusion_fraction;
    t.min_frame_terms = min_frame_terms;
    t.min_pivot_ratio = min_pivot_ratio;
    t.ray_min_cosine = ray_min_cosine;
    t.estimate_quadrics = estimate_quadrics;
    return t;
  }

  void validate() const;  // throws InputError "field: problem"
};

/// block_memory_mb in bytes.
inline std::size_t block_memory_bytes(const JointParams& p) {
  return static_cast<std::size_t>(p.block_memory_mb * 1024.0 * 1024.0);
}

}  // namespace jpcr
