// Rendered test frames for the curvature estimators: one analytic object in a room, seen by the
// synthetic camera, with the pixels whose whole neighbourhood pattern lies on the object.
#pragma once

#include <vector>

#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/io/synthetic_trajectory.hpp"
#include "jpcr/quadric/neighbourhood_pattern.hpp"

namespace jpcr::test {

inline Eigen::Isometry3d look_from(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = look_at(eye, target, Eigen::Vector3d::UnitZ());
  T.translation() = eye;
  return T;
}

/// A 10 m room (floor at z = 0) with `object` in it.
inline SyntheticScene room_with(const Surface& object) {
  SyntheticScene scene;
  scene.surfaces = {
      Box{Eigen::Vector3d(0, 0, 1.5), Eigen::Vector3d(10, 10, 3), Eigen::Matrix3d::Identity()},
      object};
  return scene;
}

/// Pixels where the centre and every sample of `pattern` see surface `index` with defined
/// curvature (no crease or silhouette inside the neighbourhood). With `flat`, every sample must
/// also have the centre's normal: one face of a box, not two faces meeting at a room corner.
/// `max_incidence_deg` drops pixels seen more obliquely (angle between view ray and normal).
inline std::vector<std::pair<int, int>> interior_pixels(const SyntheticFrame& f, int index,
                                                        const NeighbourhoodPattern& pattern,
                                                        bool flat = false,
                                                        double max_incidence_deg = 90.0) {
  const CameraIntrinsics& cam = f.frame.camera;
  std::vector<std::pair<int, int>> pixels;
  for (int v = 0; v < f.surface.height(); ++v) {
    for (int u = 0; u < f.surface.width(); ++u) {
      if (f.surface(u, v) != index) continue;
      const Eigen::Vector3f ray =
          Eigen::Vector3f((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1).normalized();
      if (-ray.dot(f.normals(u, v)) < std::cos(max_incidence_deg * M_PI / 180.0)) continue;
      bool inside = true;
      for (const PixelOffset& o : pattern.offsets) {
        const int su = u + o.du, sv = v + o.dv;
        if (!f.surface.in_bounds(su, sv) || f.surface(su, sv) != index ||
            !std::isfinite(f.curvature(su, sv).x()) ||
            (flat && f.normals(su, sv).dot(f.normals(u, v)) < 0.9999f)) {
          inside = false;
          break;
        }
      }
      if (inside) pixels.emplace_back(u, v);
    }
  }
  return pixels;
}

}  // namespace jpcr::test
