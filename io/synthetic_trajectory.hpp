// Camera trajectories for synthetic sequences: exact camera-to-world poses (method.md §1, TUM
// convention) around a scene's viewpoint (SceneView).
//
//   Trajectory t = make_trajectory(TrajectoryKind::kWalk, scene.view, 100, {}, /*seed=*/7);
//
// - rail:  translation only along view.rail_direction, centred on view.eye, one frame per
//          rail_step (10 mm: the paper's drift rig), with the fixed rotation looking at target.
// - orbit: a horizontal circle (about view.up) around view.target through view.eye, always
//          looking at the target, orbit_step degrees per frame.
// - walk:  smooth random 6-DoF hand-held motion around view.eye, looking at view.target with a
//          small random head rotation; seeded, and bounded in speed (see TrajectoryParams).
// Timestamps are start_time + i / rate, rounded to whole microseconds so that their 6-decimal
// text (TUM file lists) reads back exactly.
#pragma once

#include <cstdint>
#include <string>

#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/quadric/frame.hpp"

namespace jpcr {

enum class TrajectoryKind { kRail, kOrbit, kWalk };

/// "rail", "orbit" or "walk"; throws InputError otherwise.
TrajectoryKind parse_trajectory_kind(const std::string& text);
std::string to_string(TrajectoryKind kind);

struct TrajectoryParams {
  double rate = 30.0;        // Hz, frames per second
  double start_time = 0.0;   // s, timestamp of the first frame
  double rail_step = 0.01;   // m per frame along the rail (the paper's rig: one frame per 10 mm)
  double orbit_step = 0.25;  // deg per frame around the target
  // The walk sums three sinusoids per degree of freedom with random periods in
  // [walk_min_period, walk_max_period], scaled so that the speeds below are upper bounds.
  double walk_max_speed = 0.35;      // m/s, bound on the translational speed
  double walk_max_head_rate = 15.0;  // deg/s, bound on the head rotation's rate (looking at the
                                     // target while moving adds at most speed / distance)
  double walk_min_period = 3.0;      // s
  double walk_max_period = 10.0;     // s

  /// Throws InputError "field: problem" for the first field that is not positive (or periods
  /// out of order).
  void validate() const;
};

/// `frames` ≥ 1 stamped camera-to-world poses; `seed` matters only for the walk.
Trajectory make_trajectory(TrajectoryKind kind, const SceneView& view, int frames,
                           const TrajectoryParams& params = {}, std::uint64_t seed = 0);

/// Camera-to-world rotation of a camera at `eye` looking at `target`: the camera's z axis points
/// at the target, x to the right and y down in the image, with `up` up.
Eigen::Matrix3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                        const Eigen::Vector3d& up);

}  // namespace jpcr
