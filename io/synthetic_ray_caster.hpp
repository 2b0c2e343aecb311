// Ray-traced RGB-D frames of a synthetic scene with exact per-pixel ground truth.
//
//   SyntheticFrame f = render(scene, synthetic_camera(), pose_wc, parse_noise("range:1"), seed, i);
//   f.frame            the depth frame a sensor would give (noisy depth in metres, 0 = none)
//   f.curvature(u, v)  exact (κ1, κ2) of the surface seen at the pixel centre, NaN where none
//
// One ray through each pixel centre of an ideal pinhole camera (method.md §1: depth is z along
// the optical axis). Rendering is multithreaded (OpenMP) and deterministic: a frame is a pure
// function of (scene, camera, pose, noise, seed, frame_index).
#pragma once

#include <cstdint>

#include "jpcr/io/synthetic_noise.hpp"
#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/quadric/frame.hpp"
#include "jpcr/quadric/vertex_map.hpp"

namespace jpcr {

struct SyntheticFrame {
  /// Timestamp, noisy depth (m, 0 = no measurement: a dropout of the noise model, or beyond
  /// what a depth PNG holds, 65535 / depth_scale), the camera, and colour shaded by normal.
  Frame frame;
  Eigen::Isometry3d pose_wc = Eigen::Isometry3d::Identity();  // exact camera-to-world pose
  DepthImage exact_depth;  // noise-free z (m), 0 where the ray hits nothing
  /// Principal curvatures κ1 ≥ κ2 (1/m) with method.md §1's sign (normal toward the camera, a
  /// surface bulging toward the camera is negative). NaN where the depth has no measurement,
  /// and where the pixel's footprint is not one smooth patch — the rays through its four
  /// corners hit another surface, face or side than its centre (box edges, cylinder rims, the
  /// rim of an open tube between its outside and inside, silhouettes) or the same one more than
  /// 5 % of the range farther or nearer (a surface hiding another part of itself, a torus's
  /// near tube its far tube; and pixels seen within about 6° of grazing at 160 px wide, 1.5° at
  /// 640 px) — since curvature is undefined on a crease. A hidden edge whose corner rays meet
  /// the surface between the two ranges can still pass (4 pairs of neighbours on the
  /// torus_saddle view at 160x120, 124 without the range test).
  CurvatureImage curvature;
  NormalMap normals;  // camera frame, unit, toward the camera; NaN where no depth is measured
  Image<std::int32_t> surface;  // index into scene.surfaces, −1 where none
};

/// The default synthetic camera (configs/synthetic.yaml): 640x480 with fx = fy = 550 and the
/// principal point at the centre, scaled to width x height with the same field of view.
CameraIntrinsics synthetic_camera(int width = 640, int height = 480);

/// Throws InputError when the camera is invalid or has lens distortion (the renderer is an
/// ideal pinhole).
void check_synthetic_camera(const CameraIntrinsics& camera);

/// Renders one frame; `frame_index` and `seed` select the noise. Throws InputError when the
/// camera is invalid or has lens distortion (the renderer is an ideal pinhole).
SyntheticFrame render(const SyntheticScene& scene, const CameraIntrinsics& camera,
                      const Eigen::Isometry3d& pose_wc, const NoiseModel& noise = {},
                      std::uint64_t seed = 0, std::uint64_t frame_index = 0,
                      double timestamp = 0.0);

/// A colour picture of a normal map: RGB = 255 (1 + (n_x, n_y, −n_z)) / 2 in camera axes,
/// black where there is no normal.
ColorImage shade_normals(const NormalMap& normals);

}  // namespace jpcr
