// The analytic surfaces of synthetic scenes: planes, spheres, cylinders, tori and boxes, each with
// an exact ray intersection, surface normal and pair of principal curvatures.
//
// Curvature sign (method.md §1): curvatures are taken about a unit normal, and a surface that
// bulges toward its normal has negative curvature. Here every hit reports the curvature about the
// *outward* normal (the outside of a ball: κ1 = κ2 = −1/R); cast_ray() in synthetic_scene.hpp
// turns it toward the camera, which flips the sign when the camera sees the inside.
#pragma once

#include <optional>

#include <Eigen/Core>

namespace jpcr {

/// A ray origin + t · direction with a unit direction, so t is the range in metres.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

/// The first intersection of a ray with one surface, in the surface's own terms.
struct SurfacePoint {
  double t = 0.0;                                             // range along the ray (m)
  Eigen::Vector3d outward_normal = Eigen::Vector3d::UnitZ();  // unit
  Eigen::Vector2d curvature = Eigen::Vector2d::Zero();  // κ1 ≥ κ2 about outward_normal (1/m)
  int patch = 0;  // the smooth piece that was hit: box face 0–5, cylinder side 0 or cap 1–2
};

/// An infinite plane; `normal` (unit) is its outward side.
struct Plane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

struct Sphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;  // m
};

/// A circular cylinder around the line through `center` along `axis` (unit). length 0 means
/// infinite; a finite cylinder is closed by flat discs when `capped`, else it is an open tube
/// whose inside is visible through the ends.
struct Cylinder {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double radius = 1.0;  // m
  double length = 0.0;  // m, 0 = infinite
  bool capped = true;
};

/// A ring torus: the tube of radius `minor_radius` around the circle of radius `major_radius`
/// centred at `center` in the plane normal to `axis` (unit). minor_radius < major_radius.
struct Torus {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double major_radius = 1.0;   // m
  double minor_radius = 0.25;  // m
};

/// A rectangular box. `rotation` maps box axes to world axes (columns are the box's x, y, z).
/// Seen from inside, its faces are the walls, floor and ceiling of a room.
struct Box {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Ones();  // full edge lengths (m)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
};

/// The nearest intersection with t > t_min, if any. A ray starting inside a closed surface hits
/// its inside.
std::optional<SurfacePoint> intersect(const Plane& plane, const Ray& ray, double t_min);
std::optional<SurfacePoint> intersect(const Sphere& sphere, const Ray& ray, double t_min);
std::optional<SurfacePoint> intersect(const Cylinder& cylinder, const Ray& ray, double t_min);
std::optional<SurfacePoint> intersect(const Torus& torus, const Ray& ray, double t_min);
std::optional<SurfacePoint> intersect(const Box& box, const Ray& ray, double t_min);

/// Whether `point` lies strictly inside the solid a closed surface bounds: a sphere, a torus, a
/// box, a finite capped cylinder. Planes, open tubes and infinite cylinders bound none: false.
bool encloses(const Plane& plane, const Eigen::Vector3d& point);
bool encloses(const Sphere& sphere, const Eigen::Vector3d& point);
bool encloses(const Cylinder& cylinder, const Eigen::Vector3d& point);
bool encloses(const Torus& torus, const Eigen::Vector3d& point);
bool encloses(const Box& box, const Eigen::Vector3d& point);

/// A sphere that encloses a bounded surface (for culling); radius is infinite for planes and
/// infinite cylinders.
struct BoundingSphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.0;  // m
};
BoundingSphere bounding_sphere(const Plane& plane);
BoundingSphere bounding_sphere(const Sphere& sphere);
BoundingSphere bounding_sphere(const Cylinder& cylinder);
BoundingSphere bounding_sphere(const Torus& torus);
BoundingSphere bounding_sphere(const Box& box);

/// Principal curvatures (κ1 ≥ κ2, about the outward normal) of a torus at a surface point:
/// −1/r around the tube and −(ρ − R) / (r ρ) along the parallel, with ρ the distance of the
/// point from the axis (the classic κ = cos θ / (R + r cos θ), ρ = R + r cos θ, in our sign).
Eigen::Vector2d torus_curvature(const Torus& torus, const Eigen::Vector3d& point);

}  // namespace jpcr
