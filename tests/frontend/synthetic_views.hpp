// Exact synthetic frames for the front-end tests: a scene rendered noise-free at chosen poses.
#pragma once

#include <cmath>

#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/io/synthetic_trajectory.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr::test {

constexpr double kDeg = M_PI / 180.0;

inline Eigen::Isometry3d look_from(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = look_at(eye, target, Eigen::Vector3d::UnitZ());
  T.translation() = eye;
  return T;
}

/// The room_spheres scene from its default viewpoint.
inline const SyntheticScene& room() {
  static const SyntheticScene scene = load_scene("room_spheres");
  return scene;
}

inline Eigen::Isometry3d room_view() {
  return look_from(room().view.eye, room().view.target);
}

inline Frame render_at(const SyntheticScene& scene, const Eigen::Isometry3d& T_wc, int width = 640,
                       int height = 480) {
  return render(scene, synthetic_camera(width, height), T_wc).frame;
}

/// A rigid motion of `translation` metres and `rotation` radians about fixed, generic axes.
inline Eigen::Isometry3d motion(double translation, double rotation) {
  Vector6d xi;
  xi.head<3>() = Eigen::Vector3d(1.0, -0.6, 0.4).normalized() * translation;
  xi.tail<3>() = Eigen::Vector3d(-0.3, 1.0, 0.5).normalized() * rotation;
  Eigen::Isometry3d T = se3_exp(xi);
  T.translation() = xi.head<3>();  // exactly `translation` long
  return T;
}

inline double translation_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.inverse() * b).translation().norm();
}

inline double rotation_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return rotation_angle((a.inverse() * b).linear());
}

}  // namespace jpcr::test
