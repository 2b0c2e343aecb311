// Initial normals for the quadric fits (method.md §3): a least-squares plane through the valid
// vertices of a (2h+1)x(2h+1) window (7x7 by default), oriented toward the camera (n·X < 0).
#pragma once

#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct NormalEstimationParams {
  int half_window = 3;          // h: the window is (2h+1)² pixels (7x7 by default)
  int min_points = 6;           // fewer valid window points → no normal
  float max_depth_jump = 0.1f;  // fraction of the centre's depth: window points whose depth
                                // differs more are on another surface and left out of the plane
  /// A quadrant of the window ((h+1)² pixels sharing the centre) whose plane residual is this many
  /// times below the window's gives the normal instead: the window then holds no single smooth
  /// surface (a depth step below max_depth_jump, a crease; plane_normal_kernel.hpp,
  /// choose_quadrant). 0: always the window's plane (method.md §3 as written).
  float quadrant_ratio = 100.0f;
  void validate() const;  // throws InputError "field: problem"
};

/// One normal per pixel (camera frame, unit, n·X < 0); NaN where the centre has no vertex, too few
/// window points remain or the points are collinear. `quadrant_tilt`, where given, receives per
/// pixel the angle (rad) by which a quadrant's normal replaced the window's plane: 0 where the
/// window's plane is the normal (or there is none), above a degree or so where the window
/// straddles a crease or a step (the joint refiners leave those quadrics out, JointParams).
NormalMap estimate_normals(const VertexMap& vertices, const NormalEstimationParams& params = {},
                           Image<float>* quadrant_tilt = nullptr);

}  // namespace jpcr
