#include "jpcr/io/synthetic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>

#include <yaml-cpp/yaml.h>
#include <Eigen/Geometry>

#include "jpcr/io/atomic_file.hpp"
#include "jpcr/io/yaml_reader.hpp"
#include "jpcr/quadric/error.hpp"

namespace fs = std::filesystem;

namespace jpcr {

namespace {

// ---- YAML → surfaces --------------------------------------------------------------------------

void require(YamlSection& yaml, const std::string& key, const std::string& what) {
  if (!yaml.has(key)) yaml.fail(key, "missing (" + what + ")");
}

// Absent (or null) keeps `fallback`.
Eigen::Vector3d read_vector(YamlSection& yaml, const std::string& key,
                            const Eigen::Vector3d& fallback = Eigen::Vector3d::Zero()) {
  std::array<double, 3> v{fallback.x(), fallback.y(), fallback.z()};
  yaml.read(key, v);
  return {v[0], v[1], v[2]};
}

Eigen::Vector3d read_point(YamlSection& yaml, const std::string& key) {
  require(yaml, key, "[x, y, z] in metres");
  return read_vector(yaml, key);
}

// A unit direction; required unless a fallback is given.
Eigen::Vector3d read_direction(YamlSection& yaml, const std::string& key,
                               const std::optional<Eigen::Vector3d>& fallback = std::nullopt) {
  if (!fallback) require(yaml, key, "a direction [x, y, z]");
  const Eigen::Vector3d v = read_vector(yaml, key, fallback.value_or(Eigen::Vector3d::Zero()));
  if (!(v.norm() > 1e-9)) yaml.fail(key, "must be a non-zero direction");
  return v.normalized();
}

double read_length(YamlSection& yaml, const std::string& key) {
  require(yaml, key, "a length in metres");
  double value = 0.0;
  yaml.read(key, value);
  if (!(value > 0.0)) yaml.fail(key, "must be positive (m)");
  return value;
}

Surface read_surface(YamlSection& yaml) {
  require(yaml, "type", "one of plane, sphere, cylinder, torus, box");
  std::string type;
  yaml.read_choice("type", type, {"plane", "sphere", "cylinder", "torus", "box"});
  if (type == "plane") return Plane{read_point(yaml, "point"), read_direction(yaml, "normal")};
  if (type == "sphere") return Sphere{read_point(yaml, "center"), read_length(yaml, "radius")};
  if (type == "cylinder") {
    Cylinder c{read_point(yaml, "center"), read_direction(yaml, "axis"),
               read_length(yaml, "radius")};
    yaml.read("length", c.length);
    if (c.length < 0.0) yaml.fail("length", "must be positive (m), or 0 for infinite");
    yaml.read("capped", c.capped);
    return c;
  }
  if (type == "torus") {
    Torus t{read_point(yaml, "center"), read_direction(yaml, "axis"),
            read_length(yaml, "major_radius"), read_length(yaml, "minor_radius")};
    if (t.minor_radius >= t.major_radius) {
      yaml.fail("minor_radius", "must be smaller than major_radius (a ring torus)");
    }
    return t;
  }
  Box box{read_point(yaml, "center"), read_point(yaml, "size")};
  for (int i = 0; i < 3; ++i) {
    if (!(box.size[i] > 0.0)) yaml.fail("size", "edge lengths must be positive (m)");
  }
  const Eigen::Vector3d rad = read_vector(yaml, "rotation_deg") * (EIGEN_PI / 180.0);
  box.rotation = (Eigen::AngleAxisd(rad.z(), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(rad.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(rad.x(), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  return box;
}

SceneView read_view(YamlSection yaml) {
  SceneView view;
  view.eye = read_point(yaml, "eye");
  view.target = read_point(yaml, "target");
  view.up = read_direction(yaml, "up", Eigen::Vector3d::UnitZ());
  view.rail_direction = read_direction(yaml, "rail_direction", Eigen::Vector3d::UnitX());
  const Eigen::Vector3d forward = view.target - view.eye;
  if (!(forward.norm() > 1e-6)) yaml.fail("target", "must differ from eye");
  if (forward.normalized().cross(view.up).norm() < 1e-3) {
    yaml.fail("up", "must not be parallel to the viewing direction (target − eye)");
  }
  yaml.finish();
  return view;
}

// ---- Scene files ------------------------------------------------------------------------------

bool is_path(const std::string& name_or_path) {
  const auto ends_with = [&](const std::string& suffix) {
    return name_or_path.size() >= suffix.size() &&
           name_or_path.compare(name_or_path.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  return name_or_path.find('/') != std::string::npos || ends_with(".yaml") || ends_with(".yml");
}

// <prefix>/share/jpcr/configs/scenes for the prefix the running program is installed in.
std::string scenes_next_to_program() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  return (exe.parent_path().parent_path() / "share/jpcr/configs/scenes").string();
}

// ---- Ray casting ------------------------------------------------------------------------------

// The nearest hit over the surfaces with the given indices, oriented toward the ray origin.
template <typename Indices>
std::optional<SurfaceHit> nearest_hit(const SyntheticScene& scene, const Ray& ray,
                                      const Indices& indices, double t_min) {
  std::optional<SurfacePoint> nearest;
  int surface = -1;
  for (const int i : indices) {
    const std::optional<SurfacePoint> hit =
        std::visit([&](const auto& s) { return intersect(s, ray, t_min); }, scene.surfaces[i]);
    if (hit && (!nearest || hit->t < nearest->t)) {
      nearest = hit;
      surface = i;
    }
  }
  if (!nearest) return std::nullopt;
  SurfaceHit hit;
  hit.range = nearest->t;
  hit.point = ray.origin + nearest->t * ray.direction;
  hit.surface = surface;
  hit.patch = nearest->patch;
  if (nearest->outward_normal.dot(ray.direction) < 0.0) {
    hit.normal = nearest->outward_normal;
    hit.curvature = nearest->curvature;
  } else {
    // The camera sees the inside (or back): turning the normal around negates the curvatures,
    // and κ1 ≥ κ2 swaps them (method.md §1: the inside of a bowl is positive).
    hit.inside = true;
    hit.normal = -nearest->outward_normal;
    hit.curvature = Eigen::Vector2d(-nearest->curvature.y(), -nearest->curvature.x());
  }
  return hit;
}

// 0, 1, ..., n − 1 without storing them.
struct AllIndices {
  struct Iterator {
    int i;
    int operator*() const { return i; }
    Iterator& operator++() {
      ++i;
      return *this;
    }
    bool operator!=(const Iterator& other) const { return i != other.i; }
  };
  int n;
  Iterator begin() const { return {0}; }
  Iterator end() const { return {n}; }
};

}  // namespace

std::optional<SurfaceHit> cast_ray(const SyntheticScene& scene, const Ray& ray, double t_min) {
  return nearest_hit(scene, ray, AllIndices{static_cast<int>(scene.surfaces.size())}, t_min);
}

std::optional<SurfaceHit> cast_ray(const SyntheticScene& scene, const Ray& ray,
                                   const std::vector<int>& candidates, double t_min) {
  return nearest_hit(scene, ray, candidates, t_min);
}

BoundingSphere bounding_sphere(const Surface& surface) {
  return std::visit([](const auto& s) { return jpcr::bounding_sphere(s); }, surface);
}

bool encloses(const Surface& surface, const Eigen::Vector3d& point) {
  return std::visit([&](const auto& s) { return jpcr::encloses(s, point); }, surface);
}

void check_cameras_outside_solids(const SyntheticScene& scene, const Trajectory& trajectory) {
  static const char* const kTypes[] = {"plane", "sphere", "cylinder", "torus", "box"};
  for (std::size_t k = 0; k < scene.surfaces.size(); ++k) {
    const Surface& surface = scene.surfaces[k];
    if (encloses(surface, scene.view.eye)) continue;  // the room the scene is seen from
    for (std::size_t i = 0; i < trajectory.size(); ++i) {
      const Eigen::Vector3d eye = trajectory[i].pose.translation();
      if (!encloses(surface, eye)) continue;
      char where[96];
      std::snprintf(where, sizeof where, "(%.3f, %.3f, %.3f)", eye.x(), eye.y(), eye.z());
      throw InputError("scene " + scene.name + ": the camera of frame " + std::to_string(i) +
                       " at " + where + " m is inside surface " + std::to_string(k) + " (a " +
                       kTypes[surface.index()] +
                       "): the trajectory leaves the free space (try another seed, fewer "
                       "frames or another trajectory)");
    }
  }
}

SyntheticScene parse_scene(const std::string& yaml_text, const std::string& file,
                           const std::string& name) {
  const YAML::Node root = parse_yaml(yaml_text, file);
  YamlSection yaml(root, file);
  SyntheticScene scene;
  scene.name = name;
  yaml.read("description", scene.description);
  require(yaml, "view", "a map with eye and target");
  scene.view = read_view(yaml.section("view"));
  require(yaml, "surfaces", "a list of surfaces");
  for (YamlSection& item : yaml.sections("surfaces")) {
    scene.surfaces.push_back(read_surface(item));
    item.finish();
  }
  if (scene.surfaces.empty()) yaml.fail("surfaces", "a scene needs at least one surface");
  yaml.finish();
  return scene;
}

std::vector<std::string> scene_search_path() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("JPCR_SCENE_PATH")) {
    std::string list = env;
    for (std::size_t start = 0; start <= list.size();) {
      const std::size_t end = std::min(list.find(':', start), list.size());
      if (end > start) dirs.push_back(list.substr(start, end - start));
      start = end + 1;
    }
  }
  if (const std::string next = scenes_next_to_program(); !next.empty()) dirs.push_back(next);
  dirs.push_back(JPCR_INSTALL_SCENE_DIR);
  dirs.push_back(JPCR_SOURCE_SCENE_DIR);
  return dirs;
}

std::string find_scene_file(const std::string& name_or_path) {
  std::error_code ec;
  if (is_path(name_or_path)) {
    if (!fs::is_regular_file(name_or_path, ec)) {
      throw InputError(name_or_path + (fs::exists(name_or_path, ec)
                                           ? ": is no scene file (a directory or a device?)"
                                           : ": scene file does not exist"));
    }
    return name_or_path;
  }
  std::string searched;
  for (const std::string& dir : scene_search_path()) {
    const fs::path file = fs::path(dir) / (name_or_path + ".yaml");
    if (fs::is_regular_file(file, ec)) return file.string();
    searched += "\n  " + dir;
  }
  throw InputError("scene '" + name_or_path + "' not found (give a scene name or a .yaml path); " +
                   "looked for " + name_or_path + ".yaml in:" + searched);
}

SyntheticScene load_scene(const std::string& name_or_path) {
  const std::string file = find_scene_file(name_or_path);
  return parse_scene(read_file(file), file, fs::path(file).stem().string());
}

std::vector<std::string> available_scenes() {
  std::set<std::string> names;
  std::error_code ec;
  for (const std::string& dir : scene_search_path()) {
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->path().extension() == ".yaml") names.insert(it->path().stem().string());
    }
  }
  return {names.begin(), names.end()};
}

}  // namespace jpcr
