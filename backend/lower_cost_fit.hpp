// Quad IT's step test over a whole window, applied to the joint refiners' quadrics once they
// have converged (JointParams::keep_lower_cost_fit).
//
// The joint loop (run_joint_refinement) accepts a step when the window's total cost falls, so a
// single quadric may end with a higher cost of its own than its Quad IT start: its step is part
// of a joint Gauss-Newton step that the other quadrics and the poses pay for. Quad IT keeps a step
// only if it does not raise the quadric's gated cost Σ w(e) e² (quadric_fit_kernel.hpp). Here,
// with the refined poses fixed, the cost separates into one term per quadric, and each quadric
// keeps whichever of its refined and initial fits has the lower gated cost over every frame's
// samples; so the window's gated cost at the refined poses can only fall, and the poses do not
// change.
//
// Measured (640x480 4-frame walks, 1 % range noise, J-ftf with the report's pose parameters, the
// first three frames' curvature against the ground truth, RMS 1/m, all pixels / interior): about
// 4–7 k of 300 k quadrics per pair go back to Quad IT, cylinders_boxes 4.93 → 4.82 / 2.59 →
// 2.51, torus_saddle 4.23 → 4.09 / 2.81 → 2.77, room_spheres 3.63 → 3.54 / 2.76 → 2.71. The
// quadrics it restores lie in bands along creases: there the joint optimum bends the quadric
// towards the other face (a large saddle), which Quad IT's three steps stop short of.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "jpcr/backend/joint_params.hpp"
#include "jpcr/quadric/camera.hpp"
#include "jpcr/quadric/quadric_map.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

/// Where both maps hold a valid quadric and `initial`'s has the strictly lower gated cost over the
/// window (frame 1's samples around its pixel and each other frame's around the projection of
/// its centre at `poses`, associated as the joint terms are, with the weight n₀ and the gate of
/// params.quadric.fit), `refined` takes the initial quadric. Returns how many it took. `poses`
/// are T_1 = I, T_2 … T_M (frame j → frame 1). Throws std::invalid_argument on sizes that differ.
int keep_lower_cost_fits(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                         const std::vector<Eigen::Isometry3d>& poses, const JointParams& params,
                         const QuadricMap& initial, QuadricMap& refined);

}  // namespace jpcr
