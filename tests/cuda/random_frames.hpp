// Fresh random synthetic frames for the CPU/GPU parity tests (issue 7: "fresh random synthetic
// inputs"): a room with a random ball, a random cylinder and a random tilted box, seen from a
// random eye with random range noise. The seed is drawn per run and printed; JPCR_TEST_SEED
// replays one.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <random>

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

/// One random frame at width x height; the same seed gives the same frame.
inline SyntheticFrame random_frame(std::uint64_t seed, int width, int height) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto in = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  SyntheticScene scene =
      room_with(Sphere{{in(-0.4, 0.4), in(-0.2, 0.4), in(0.6, 1.6)}, in(0.1, 0.5)});
  const Eigen::Vector3d axis = Eigen::Vector3d(in(-1, 1), in(-1, 1), in(0.2, 1)).normalized();
  scene.surfaces.push_back(
      Cylinder{{in(-1.5, -0.5), in(0.5, 1.5), 1.0}, axis, in(0.1, 0.4), in(0.5, 1.5), true});
  scene.surfaces.push_back(Box{{in(0.6, 1.4), in(0.5, 1.5), in(0.3, 0.8)},
                               {in(0.2, 0.6), in(0.2, 0.6), in(0.2, 0.6)},
                               so3_exp(Eigen::Vector3d(in(-1, 1), in(-1, 1), in(-1, 1)))});
  const Eigen::Vector3d target(in(-0.3, 0.3), in(0.2, 0.8), in(0.6, 1.2));
  const Eigen::Vector3d eye(in(-0.5, 0.5), in(-2.2, -1.2), in(1.0, 1.8));
  const double noise = in(0.0, 1.0);  // % of the range (the paper's protocol, method.md §11)
  NoiseModel model;
  model.kind = NoiseKind::kRange;
  model.range_percent = noise;
  return render(scene, synthetic_camera(width, height), look_from(eye, target), model, seed);
}

}  // namespace jpcr::test
