// Synthetic scenes: a list of analytic surfaces (synthetic_surfaces.hpp) and the viewpoint the
// default trajectories start from, loaded from YAML (configs/scenes/NAME.yaml) or built in code.
//
//   SyntheticScene scene = load_scene("room_spheres");     // or a path to a .yaml file
//   std::optional<SurfaceHit> hit = cast_ray(scene, ray);  // what a ray sees, with curvature
//
// Scene YAML (strict: unknown keys and wrong types are errors naming the file, line and key):
//
//   description: free text                    # optional
//   view:                                     # where trajectories start (world frame, metres)
//     eye: [0, -1, 1.3]                       # camera position
//     target: [0, 1.5, 0.8]                   # the point it looks at (orbit centre)
//     up: [0, 0, 1]                           # optional, default +z
//     rail_direction: [1, 0, 0]               # optional, default +x
//   surfaces:
//     - {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
//     - {type: sphere, center: [0, 2, 0.5], radius: 0.5}
//     - {type: cylinder, center: [1, 2, 0.5], axis: [0, 0, 1], radius: 0.2,
//        length: 1.0, capped: true}           # length 0 (default) = infinite; capped default true
//     - {type: torus, center: [...], axis: [...], major_radius: 0.5, minor_radius: 0.15}
//     - {type: box, center: [...], size: [sx, sy, sz],
//        rotation_deg: [rx, ry, rz]}          # optional; R = Rz · Ry · Rx, about world axes
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "jpcr/io/synthetic_surfaces.hpp"
#include "jpcr/quadric/frame.hpp"

namespace jpcr {

using Surface = std::variant<Plane, Sphere, Cylinder, Torus, Box>;

/// The viewpoint of a scene: every trajectory starts at (a rail is centred on) `eye`, looking at
/// `target`, with `up` the world's up direction.
struct SceneView {
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::UnitY();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d rail_direction = Eigen::Vector3d::UnitX();
};

struct SyntheticScene {
  std::string name;  // the file stem for loaded scenes
  std::string description;
  std::vector<Surface> surfaces;
  SceneView view;
};

/// What a ray sees: the nearest surface point, oriented toward the ray origin (the camera).
struct SurfaceHit {
  double range = 0.0;  // distance from the ray origin (m)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, facing the ray origin
  /// κ1 ≥ κ2 (1/m) about `normal`, method.md §1: a ball seen from outside gives −1/R, its inside
  /// +1/R; a cylinder (0, −1/R) from outside; a plane (0, 0).
  Eigen::Vector2d curvature = Eigen::Vector2d::Zero();
  int surface = -1;     // index into SyntheticScene::surfaces
  int patch = 0;        // smooth piece of that surface (box face, cylinder side or cap)
  bool inside = false;  // the ray met the surface's inner side (a room's walls, a tube's inside)
};

/// The nearest hit with range > t_min over all surfaces of the scene.
std::optional<SurfaceHit> cast_ray(const SyntheticScene& scene, const Ray& ray, double t_min = 0.0);

/// The same over the surfaces listed in `candidates` (indices into scene.surfaces), e.g. those
/// that can be seen through a tile of pixels.
std::optional<SurfaceHit> cast_ray(const SyntheticScene& scene, const Ray& ray,
                                   const std::vector<int>& candidates, double t_min = 0.0);

BoundingSphere bounding_sphere(const Surface& surface);
bool encloses(const Surface& surface, const Eigen::Vector3d& point);

/// Throws InputError when a camera of `trajectory` lies inside a solid of the scene that does
/// not enclose the scene's own eye (a room does; a ball, a crate, a tyre does not): the
/// renderer would show the solid's inside with exact ground truth (a walk of torus_saddle,
/// seed 385, ends inside a ball). Names the frame, the surface and its index.
void check_cameras_outside_solids(const SyntheticScene& scene, const Trajectory& trajectory);

/// Loads a scene by name (NAME → NAME.yaml in scene_search_path()) or by path (anything with a
/// '/' or a .yaml/.yml suffix). Throws InputError naming the file and key on a bad scene, and
/// the directories searched when a name is not found.
SyntheticScene load_scene(const std::string& name_or_path);

/// Parses scene YAML text; `file` names it in error messages and `name` becomes scene.name.
SyntheticScene parse_scene(const std::string& yaml_text, const std::string& file,
                           const std::string& name);

/// The file load_scene() would read; throws InputError when there is none.
std::string find_scene_file(const std::string& name_or_path);

/// Directories searched for scene names, in order: $JPCR_SCENE_PATH (colon-separated), then
/// share/jpcr/configs/scenes next to the running program's prefix, the install prefix and the
/// source tree.
std::vector<std::string> scene_search_path();

/// Names of the scenes found on the search path, sorted and without duplicates.
std::vector<std::string> available_scenes();

}  // namespace jpcr
