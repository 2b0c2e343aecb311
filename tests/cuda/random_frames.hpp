// Fresh random synthetic frames for the CPU/GPU parity tests (issue 7: "fresh random synthetic
// inputs"): a room with a random ball, a random cylinder and a random tilted box, seen from a
// random eye with random range noise, and pairs of such frames for J-ftf. The seed is drawn per
// run and printed; JPCR_TEST_SEED replays one.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <random>
#include <vector>

#include "jpcr/io/synthetic_ray_caster.hpp"
#include "jpcr/quadric/se3.hpp"
#include "quadric/quadric_test_scenes.hpp"

namespace jpcr::test {

/// The seed of this run: $JPCR_TEST_SEED if set, else fresh from std::random_device.
inline std::uint64_t test_seed() {
  if (const char* s = std::getenv("JPCR_TEST_SEED")) return std::strtoull(s, nullptr, 10);
  std::random_device device;
  return (std::uint64_t{device()} << 32) ^ device();
}

struct RandomView {
  SyntheticScene scene;
  Eigen::Isometry3d camera_to_world;
  NoiseModel noise;
};

/// A random scene, eye and range noise drawn from `rng`.
inline RandomView random_view(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto in = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  RandomView view;
  view.scene = room_with(Sphere{{in(-0.4, 0.4), in(-0.2, 0.4), in(0.6, 1.6)}, in(0.1, 0.5)});
  const Eigen::Vector3d axis = Eigen::Vector3d(in(-1, 1), in(-1, 1), in(0.2, 1)).normalized();
  view.scene.surfaces.push_back(
      Cylinder{{in(-1.5, -0.5), in(0.5, 1.5), 1.0}, axis, in(0.1, 0.4), in(0.5, 1.5), true});
  view.scene.surfaces.push_back(Box{{in(0.6, 1.4), in(0.5, 1.5), in(0.3, 0.8)},
                                    {in(0.2, 0.6), in(0.2, 0.6), in(0.2, 0.6)},
                                    so3_exp(Eigen::Vector3d(in(-1, 1), in(-1, 1), in(-1, 1)))});
  const Eigen::Vector3d target(in(-0.3, 0.3), in(0.2, 0.8), in(0.6, 1.2));
  const Eigen::Vector3d eye(in(-0.5, 0.5), in(-2.2, -1.2), in(1.0, 1.8));
  view.camera_to_world = look_from(eye, target);
  view.noise.kind = NoiseKind::kRange;
  view.noise.range_percent = in(0.0, 1.0);  // % of the range (the paper's protocol, method.md §11)
  return view;
}

/// One random frame at width x height; the same seed gives the same frame.
inline SyntheticFrame random_frame(std::uint64_t seed, int width, int height) {
  std::mt19937_64 rng(seed);
  const RandomView view = random_view(rng);
  return render(view.scene, synthetic_camera(width, height), view.camera_to_world, view.noise,
                seed);
}

/// A random twist of `metres` translation and `radians` rotation along random axes.
inline Vector6d random_twist(std::mt19937_64& rng, double metres, double radians) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Vector3d t(normal(rng), normal(rng), normal(rng));
  const Eigen::Vector3d w(normal(rng), normal(rng), normal(rng));
  Vector6d xi;
  xi << t.normalized() * metres, w.normalized() * radians;
  return xi;
}

/// Two random frames of one random scene for J-ftf: frame 2 is the camera moved by a random
/// 2-4 cm / 1-2° motion, T₂ (frame 2 → frame 1) exact in `truth` and perturbed by a random
/// 1 cm / 1° in `start`.
struct RandomPair {
  CameraIntrinsics camera;
  std::vector<VertexMap> vertices;
  Eigen::Isometry3d truth, start;
};

inline RandomPair random_pair(std::uint64_t seed, int width, int height) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const RandomView view = random_view(rng);
  const Vector6d motion =
      random_twist(rng, 0.02 + 0.02 * unit(rng), (1.0 + unit(rng)) * 3.14159265358979 / 180);
  RandomPair p;
  p.camera = synthetic_camera(width, height);
  const Eigen::Isometry3d second = view.camera_to_world * se3_exp(motion);
  const Eigen::Isometry3d poses[2] = {view.camera_to_world, second};
  for (int j = 0; j < 2; ++j) {  // independent noise per frame
    const SyntheticFrame f = render(view.scene, p.camera, poses[j], view.noise, seed, j);
    p.vertices.push_back(compute_vertex_map(f.frame.depth, p.camera));
  }
  p.truth = view.camera_to_world.inverse() * second;
  p.start = se3_exp(random_twist(rng, 0.01, 3.14159265358979 / 180)) * p.truth;
  return p;
}

}  // namespace jpcr::test
