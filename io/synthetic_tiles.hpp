// Culling for the synthetic ray caster: the image is cut into square tiles, and each tile lists
// only the surfaces that a ray through it (pixel corners included) can possibly hit.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/quadric/camera.hpp"

namespace jpcr {

/// The unit direction, in camera axes, of the ray through continuous pixel coordinates (u, v).
inline Eigen::Vector3d pixel_ray_direction(const CameraIntrinsics& c, double u, double v) {
  return backproject(u, v, 1.0, c.fx, c.fy, c.cx, c.cy).normalized();
}

class SurfaceTiles {
 public:
  static constexpr int kTile = 16;  // px, edge of a tile

  /// Culls every surface against every tile's cone of rays, conservatively.
  SurfaceTiles(const SyntheticScene& scene, const CameraIntrinsics& camera,
               const Eigen::Isometry3d& pose_wc);

  /// Indices of the surfaces that a ray through pixel (u, v), or its corners, can hit.
  const std::vector<int>& at(int u, int v) const {
    return candidates_[static_cast<std::size_t>(v / kTile) * columns_ + u / kTile];
  }

 private:
  int columns_ = 0;
  std::vector<std::vector<int>> candidates_;  // per tile, row-major
};

}  // namespace jpcr
