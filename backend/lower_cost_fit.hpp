// Quad IT's step test over a whole window, applied to the joint refiners' quadrics after their
// loop (JointParams::keep_lower_cost_fit).
//
// The joint loop (run_joint_refinement) accepts a step when the window's total cost falls, so a
// single quadric may end with a higher cost of its own than its Quad IT start: its step is part
// of a joint Gauss-Newton step that the other quadrics and the poses pay for. Quad IT keeps a step
// only if it does not raise the quadric's gated cost Σ w(e) e², each weight at the fit it judges
// (NormalEquations6::gated, quadric_fit_kernel.hpp). Here, with the refined poses fixed, each
// quadric keeps whichever of its refined and initial fits has the lower such cost over the
// window's samples (frame 1's pattern and each other frame's where its centre projects, as
// associate() places it; min_frame_terms is not applied, both fits see the same samples). That
// cost is a sum over quadrics, so at the refined poses it can only fall; the poses do not change.
// It is not the loop's cost (whose weights are held at a linearisation): the report's cost,
// residual variance and covariance stay those of the loop. A refined quadric that refined_map
// marked kTooFewSamples stays so.
//
// Measured: see README ("After the loop, each quadric keeps the lower-cost fit"). On the
// report's 640x480 4-frame walks under 1 % range noise (J-ftf from ICP-ftf, the report's pose
// parameters; frames 0-2 against the ground truth, RMS 1/m, all pixels / interior) 4-8 k of
// about 300 k quadrics per pair go back to Quad IT: cylinders_boxes 4.93 → 4.82 / 2.59 → 2.51,
// torus_saddle 4.23 → 4.09 / 2.81 → 2.77, room_spheres 3.63 → 3.54 / 2.76 → 2.71. Those it
// restores lie in bands along creases, where the joint optimum bends the quadric towards the
// other face (a large saddle); Quad IT's three steps stop short of that (with 20 steps its
// error there rises too).
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "jpcr/backend/joint_params.hpp"
#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/quadric_map.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

/// Where both maps hold a valid quadric with the same centre and `initial`'s has the strictly
/// lower gated cost over the window (frame 1's samples around its pixel and each other frame's
/// around the projection of its centre at `poses`, with the weight n₀ and the gate of
/// params.quadric.fit), `refined` takes the initial quadric, curvature and direction. Returns how
/// many it took. `poses` are T_1 (taken as I), T_2 … T_M (frame j → frame 1). Throws
/// std::invalid_argument on counts or sizes that differ (frames, maps, camera).
int keep_lower_cost_fits(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                         const std::vector<Eigen::Isometry3d>& poses, const JointParams& params,
                         const QuadricMap& initial, QuadricMap& refined);

}  // namespace jpcr
