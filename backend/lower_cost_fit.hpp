// The cost half of Quad IT's step test, over a whole window, applied to the joint refiners'
// quadrics after their loop (JointParams::keep_lower_cost_fit).
//
// The joint loop (run_joint_refinement) accepts a step when the window's total cost falls, so a
// single quadric may end with a higher cost of its own than its Quad IT start: its step is part
// of a joint Gauss-Newton step that the other quadrics and the poses pay for. Quad IT keeps a step
// only if it does not raise the quadric's gated cost Σ w(e) e², each weight at the fit it judges
// (NormalEquations6::gated, quadric_fit_kernel.hpp). Here, with the refined poses fixed, each
// quadric keeps whichever of its refined and initial fits has the lower such cost over the
// window's samples (frame 1's pattern and each other frame's where its centre projects, as
// associate() places it). That cost is a sum over quadrics, so at the refined poses it can only
// fall; the poses do not change. It is not quite the loop's cost, which counts only the active
// quadrics and, for each, only the frames with min_frame_terms terms: so the report's cost,
// residual variance and covariance stay those of the loop. The other half of Quad IT's test, a
// step that leaves fewer than min_samples inliers is undone, is applied here too: where
// refined_map marked the refined quadric kTooFewSamples (fewer inliers of frame 1's samples),
// the start comes back, so the refiners return a curvature wherever Quad IT did.
//
// Measured: docs/findings.md ("After the loop, each quadric keeps the lower-cost fit"). On the
// report's 640x480 4-frame walks under 1 % range noise (J-ftf from ICP-ftf, the report's pose
// parameters; frames 0-2 against the ground truth, RMS 1/m, all pixels / interior) 3.8-8.4 k of
// about 300 k quadrics per pair go back to Quad IT: cylinders_boxes 4.934 → 4.816 / 2.593 →
// 2.508, torus_saddle 4.225 → 4.095 / 2.808 → 2.774, room_spheres 3.626 → 3.538 / 2.759 →
// 2.713. Where J-ftf was worst against Quad IT, in bands along creases, its quadrics were large
// saddles: the loop's 7-13 steps bend them towards the other face, which Quad IT's three steps
// stop short of (with 20 steps Quad IT's error there rises too).
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
/// params.quadric.fit), `refined` takes the initial quadric, curvature and direction; so it does
/// where `refined` is kTooFewSamples and `initial` valid. Returns how many it took. `poses` are T_1
/// (taken as I), T_2 … T_M (frame j → frame 1). Throws std::invalid_argument on counts or sizes
/// that differ (frames, maps, camera).
int keep_lower_cost_fits(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                         const std::vector<Eigen::Isometry3d>& poses, const JointParams& params,
                         const QuadricMap& initial, QuadricMap& refined);

}  // namespace jpcr
