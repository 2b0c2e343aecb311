#include "jpcr/io/synthetic_tiles.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace jpcr {

namespace {

constexpr double kConeSlack = 1e-9;  // rad, keeps the culling conservative under rounding

// What a cone of rays from the camera must meet for one of its rays to hit a surface, in camera
// axes: the surface's bounding sphere and, for a cylinder, the wedge of directions around the
// plane Π through the camera and the cylinder's axis. A point X within R of the axis is within R
// of Π and at least h − R from the camera (h: distance from the camera to the axis), so its
// direction is within asin(R / (h − R)) of Π.
struct Bounds {
  BoundingSphere sphere;
  std::optional<Eigen::Vector3d> wedge_normal;  // unit normal of Π
  double wedge_half_angle = 0.0;                // rad
};

Bounds camera_bounds(const Surface& surface, const Eigen::Isometry3d& camera_from_world) {
  Bounds b;
  b.sphere = bounding_sphere(surface);
  b.sphere.center = camera_from_world * b.sphere.center;
  if (const auto* cylinder = std::get_if<Cylinder>(&surface)) {
    const Eigen::Vector3d c = camera_from_world * cylinder->center;
    const Eigen::Vector3d normal = c.cross(camera_from_world.linear() * cylinder->axis);
    const double h = normal.norm();  // |c × a| with |a| = 1: the axis' distance
    if (h > 2.0 * cylinder->radius) {
      b.wedge_normal = normal / h;
      b.wedge_half_angle = std::asin(cylinder->radius / (h - cylinder->radius));
    }
  }
  return b;
}

// Whether a cone (unit axis, half-angle alpha) can meet the bounds. A ray within alpha of the
// axis is at an angle θ − alpha or more from anything seen at angle θ from the axis.
bool cone_meets(const Eigen::Vector3d& axis, double alpha, const Bounds& b) {
  const double distance = b.sphere.center.norm();
  const double radius = b.sphere.radius;
  if (std::isfinite(radius) && distance > radius) {
    const double theta = std::acos(std::clamp(axis.dot(b.sphere.center) / distance, -1.0, 1.0));
    if (theta - alpha > std::asin(radius / distance) + kConeSlack) return false;
  }
  if (b.wedge_normal) {
    const double off_plane = std::asin(std::min(1.0, std::abs(axis.dot(*b.wedge_normal))));
    if (off_plane - alpha > b.wedge_half_angle + kConeSlack) return false;
  }
  return true;
}

}  // namespace

SurfaceTiles::SurfaceTiles(const SyntheticScene& scene, const CameraIntrinsics& camera,
                           const Eigen::Isometry3d& pose_wc) {
  std::vector<Bounds> bounds;
  for (const Surface& s : scene.surfaces)
    bounds.push_back(camera_bounds(s, pose_wc.inverse()));
  columns_ = (camera.width + kTile - 1) / kTile;
  const int rows = (camera.height + kTile - 1) / kTile;
  candidates_.resize(static_cast<std::size_t>(columns_) * rows);
  for (int ty = 0; ty < rows; ++ty) {
    for (int tx = 0; tx < columns_; ++tx) {
      // The cone around the tile's rays: pixel corners run from −½ to the last pixel + ½. The
      // directions within an angle of the axis project to a convex region of the image, so the
      // tile's four corners bound the angle.
      const double u0 = tx * kTile - 0.5, u1 = std::min((tx + 1) * kTile, camera.width) - 0.5;
      const double v0 = ty * kTile - 0.5, v1 = std::min((ty + 1) * kTile, camera.height) - 0.5;
      const Eigen::Vector3d axis = pixel_ray_direction(camera, 0.5 * (u0 + u1), 0.5 * (v0 + v1));
      double alpha = 0.0;
      for (const double u : {u0, u1}) {
        for (const double v : {v0, v1}) {
          const double c = axis.dot(pixel_ray_direction(camera, u, v));
          alpha = std::max(alpha, std::acos(std::min(1.0, c)));
        }
      }
      std::vector<int>& list = candidates_[static_cast<std::size_t>(ty) * columns_ + tx];
      for (std::size_t i = 0; i < bounds.size(); ++i) {
        if (cone_meets(axis, alpha, bounds[i])) list.push_back(static_cast<int>(i));
      }
    }
  }
}

}  // namespace jpcr
