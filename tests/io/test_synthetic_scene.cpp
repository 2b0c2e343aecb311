// Scene YAML (strict, with errors naming file and key), scene lookup by name, and the shipped
// scenes: each is seen well from every pose of its default trajectories.
#include <algorithm>
#include <cstdlib>
#include <tuple>

#include <gtest/gtest.h>

#include "input_error.hpp"
#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/io/synthetic_trajectory.hpp"
#include "jpcr/quadric/error.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

using test::input_error_of;

const std::string kView = "view: {eye: [0, -2, 1], target: [0, 0, 1]}\n";

TEST(SyntheticScene, ParsesEverySurfaceType) {
  const SyntheticScene scene = parse_scene(
      "description: test\n" + kView +
          "surfaces:\n"
          "  - {type: plane, point: [0, 0, 0], normal: [0, 0, 2]}\n"
          "  - {type: sphere, center: [1, 2, 3], radius: 0.5}\n"
          "  - {type: cylinder, center: [0, 0, 0], axis: [0, 3, 0], radius: 0.2, length: 1,\n"
          "     capped: false}\n"
          "  - {type: torus, center: [0, 0, 1], axis: [1, 0, 0], major_radius: 0.5,\n"
          "     minor_radius: 0.1}\n"
          "  - {type: box, center: [0, 0, 0], size: [1, 2, 3], rotation_deg: [0, 0, 90]}\n",
      "inline.yaml", "inline");
  EXPECT_EQ(scene.name, "inline");
  EXPECT_EQ(scene.description, "test");
  ASSERT_EQ(scene.surfaces.size(), 5u);
  EXPECT_EQ(std::get<Plane>(scene.surfaces[0]).normal, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(std::get<Sphere>(scene.surfaces[1]).radius, 0.5);
  const Cylinder& c = std::get<Cylinder>(scene.surfaces[2]);
  EXPECT_EQ(c.axis, Eigen::Vector3d::UnitY());
  EXPECT_FALSE(c.capped);
  EXPECT_EQ(std::get<Torus>(scene.surfaces[3]).minor_radius, 0.1);
  const Box& b = std::get<Box>(scene.surfaces[4]);
  EXPECT_TRUE((b.rotation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_EQ(scene.view.up, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(scene.view.rail_direction, Eigen::Vector3d::UnitX());
}

TEST(SyntheticScene, BadYamlNamesFileLineAndKey) {
  test::TempDir dir;
  const auto error_for = [&](const std::string& text) {
    const std::string path = dir.write("bad.yaml", text);
    return input_error_of([&] { load_scene(path); });
  };
  const std::string sphere = "  - {type: sphere, center: [0, 0, 0], radius: 1}\n";
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {kView + "surfaces:\n" + sphere + "  - {type: sphere, center: [0, 0, 0], radius: -1}\n",
       "bad.yaml:4: key 'surfaces[1].radius': must be positive"},
      {kView + "surfaces:\n  - {type: sphere, center: [0, 0], radius: 1}\n",
       "key 'surfaces[0].center': expected a list of 3 numbers"},
      {kView + "surfaces:\n  - {type: sphere, centre: [0, 0, 0], radius: 1}\n",
       "key 'surfaces[0].center': missing"},
      {kView + "surfaces:\n  - {type: sphere, center: [0, 0, 0], radius: 1, color: red}\n",
       "unknown key 'surfaces[0].color'"},
      {kView + "surfaces:\n  - {type: cone, center: [0, 0, 0]}\n",
       "key 'surfaces[0].type': expected one of plane | sphere | cylinder | torus | box"},
      {kView + "surfaces:\n  - {center: [0, 0, 0]}\n", "key 'surfaces[0].type': missing"},
      {kView + "surfaces:\n  - {type: sphere, center: [0, 0, 0], radius: big}\n",
       "key 'surfaces[0].radius': expected a finite number, got 'big'"},
      {kView + "surfaces:\n  - {type: plane, point: [0, 0, 0], normal: [0, 0, 0]}\n",
       "key 'surfaces[0].normal': must be a non-zero direction"},
      {kView + "surfaces:\n  - {type: torus, center: [0, 0, 0], axis: [0, 0, 1], "
               "major_radius: 0.2, minor_radius: 0.3}\n",
       "key 'surfaces[0].minor_radius': must be smaller than major_radius"},
      {kView + "surfaces:\n  - {type: box, center: [0, 0, 0], size: [1, 0, 1]}\n",
       "key 'surfaces[0].size': edge lengths must be positive"},
      {kView + "surfaces:\n  - {type: cylinder, center: [0, 0, 0], axis: [0, 0, 1], radius: 1, "
               "capped: maybe}\n",
       "key 'surfaces[0].capped': expected true or false"},
      {kView + "surfaces: {type: sphere}\n", "key 'surfaces': expected a list of maps"},
      {kView + "surfaces: []\n", "key 'surfaces': a scene needs at least one surface"},
      {kView + "surfaces:\n  - 5\n", "'surfaces[0]' must be a map"},
      {"surfaces:\n" + sphere, "key 'view': missing"},
      {"view: {eye: [0, 0, 1], target: [0, 0, 1]}\nsurfaces:\n" + sphere,
       "key 'view.target': must differ from eye"},
      {"view: {eye: [0, 0, 0], target: [0, 0, 1]}\nsurfaces:\n" + sphere,
       "key 'view.up': must not be parallel"},
      {kView + "surfaces:\n" + sphere + "lights: 2\n", "unknown key 'lights'"},
      {kView + "surfaces: [\n", "YAML syntax error"},
  };
  for (const Case& c : cases) {
    const std::string message = error_for(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos)
        << "got: " << message << "\nwanted: " << c.expected;
    EXPECT_NE(message.find("bad.yaml"), std::string::npos) << message;
  }
}

TEST(SyntheticScene, NamesResolveOnTheSearchPathAndPathsAsGiven) {
  const std::vector<std::string> names = available_scenes();
  for (const char* expected : {"room_spheres", "cylinders_boxes", "torus_saddle", "rail_wall"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
    const SyntheticScene scene = load_scene(expected);
    EXPECT_EQ(scene.name, expected);
    EXPECT_FALSE(scene.description.empty());
  }
  const std::string missing = input_error_of([] { load_scene("no_such_scene"); });
  EXPECT_NE(missing.find("scene 'no_such_scene' not found"), std::string::npos) << missing;
  EXPECT_NE(missing.find(std::string(JPCR_SOURCE_DIR) + "/configs/scenes"), std::string::npos);
  EXPECT_NE(input_error_of([] { load_scene("nowhere/x.yaml"); }).find("scene file does not exist"),
            std::string::npos);

  // $JPCR_SCENE_PATH comes first.
  test::TempDir dir;
  dir.write("room_spheres.yaml",
            kView + "surfaces:\n  - {type: sphere, center: [0, 0, 1], radius: 0.25}\n");
  setenv("JPCR_SCENE_PATH", ("/does/not/exist:" + dir.path()).c_str(), 1);
  const SyntheticScene own = load_scene("room_spheres");
  unsetenv("JPCR_SCENE_PATH");
  ASSERT_EQ(own.surfaces.size(), 1u);
  EXPECT_EQ(std::get<Sphere>(own.surfaces[0]).radius, 0.25);
}

// What a scene looks like from its default trajectories, at low resolution.
struct Coverage {
  double surface = 1.0;   // least fraction of pixels with a surface over the sampled poses
  double in_range = 1.0;  // least fraction with depth in [0.8, 4.5] m
  double curved = 1.0;    // least fraction with non-zero ground-truth curvature
};

Coverage coverage(const SyntheticScene& scene, TrajectoryKind kind, int frames, int every) {
  const CameraIntrinsics camera = synthetic_camera(64, 48);
  const Trajectory trajectory = make_trajectory(kind, scene.view, frames, {}, 1);
  Coverage c;
  for (int i = 0; i < frames; i += every) {
    const SyntheticFrame f = render(scene, camera, trajectory[static_cast<std::size_t>(i)].pose);
    double surface = 0, in_range = 0, curved = 0;
    for (std::size_t p = 0; p < f.exact_depth.size(); ++p) {
      const float z = f.exact_depth[p];
      surface += z > 0.0f;
      in_range += z >= 0.8f && z <= 4.5f;
      curved += f.curvature[p].cwiseAbs().maxCoeff() > 1e-6f;  // NaN compares false
    }
    const double n = static_cast<double>(f.exact_depth.size());
    c.surface = std::min(c.surface, surface / n);
    c.in_range = std::min(c.in_range, in_range / n);
    c.curved = std::min(c.curved, curved / n);
  }
  return c;
}

TEST(SyntheticScene, ShippedScenesFillTheViewFromEveryDefaultPose) {
  // Every pose sampled from a full orbit, a 900-frame walk and a 3 m rail of the room scenes
  // sees a surface in every pixel; measured minima at 64x48: 81 % of the pixels at 0.8–4.5 m
  // (cylinders_boxes, orbit) and 14.5 % curved (cylinders_boxes, rail). rail_wall along a 12 m
  // rail: all at 0.8–4.5 m, 4.6 % curved. The thresholds leave a margin below those.
  for (const char* name : {"room_spheres", "cylinders_boxes", "torus_saddle"}) {
    const SyntheticScene scene = load_scene(name);
    for (const auto& [kind, frames, every] :
         {std::tuple{TrajectoryKind::kOrbit, 1440, 40}, std::tuple{TrajectoryKind::kWalk, 900, 60},
          std::tuple{TrajectoryKind::kRail, 300, 30}}) {
      const Coverage c = coverage(scene, kind, frames, every);
      EXPECT_EQ(c.surface, 1.0) << name << " " << to_string(kind);
      EXPECT_GE(c.in_range, 0.75) << name << " " << to_string(kind);
      EXPECT_GE(c.curved, 0.10) << name << " " << to_string(kind);
    }
  }
  const Coverage wall = coverage(load_scene("rail_wall"), TrajectoryKind::kRail, 1200, 50);
  EXPECT_EQ(wall.surface, 1.0);
  EXPECT_EQ(wall.in_range, 1.0);
  EXPECT_GE(wall.curved, 0.02);  // "a mostly planar wall with some relief"
}

// From frame 83 on, a walk of torus_saddle (seed 385) is inside a ball (the scene's last, 0.30 m
// from its eye), whose inside the renderer showed with exact ground truth: refused, naming the
// frame and the ball. The room the scene is seen from encloses every camera and is no solid.
TEST(SyntheticScene, ACameraInsideASolidIsRefused) {
  const SyntheticScene scene = load_scene("torus_saddle");
  const Trajectory walk = make_trajectory(TrajectoryKind::kWalk, scene.view, 100, {}, 385);
  const std::string error = input_error_of([&] { check_cameras_outside_solids(scene, walk); });
  EXPECT_EQ(
      error.rfind("scene torus_saddle: the camera of frame 83 at (0.132, -2.143, 1.244) m", 0), 0u)
      << error;
  EXPECT_NE(error.find("m is inside surface 18 (a sphere): the trajectory leaves the free space"),
            std::string::npos)
      << error;
  const Trajectory first_frames(walk.begin(), walk.begin() + 80);
  EXPECT_EQ(input_error_of([&] { check_cameras_outside_solids(scene, first_frames); }),
            "<no error>");
  ASSERT_TRUE(encloses(scene.surfaces[0], scene.view.eye));  // the round room
}

}  // namespace
}  // namespace jpcr
