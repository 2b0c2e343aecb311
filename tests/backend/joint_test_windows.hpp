// Rendered windows for the joint refiners: frames of the room_spheres scene from nearby poses,
// with the exact relative poses T_j (frame j → frame 1), and pose perturbations.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../quadric/quadric_test_scenes.hpp"
#include "jpcr/backend/joint_pixel_kernel.hpp"
#include "jpcr/backend/refiner.hpp"
#include "jpcr/io/synthetic_scene.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr::test {

struct JointTestWindow {
  CameraIntrinsics camera;
  std::vector<SyntheticFrame> frames;
  std::vector<VertexMap> vertices;
  std::vector<Eigen::Isometry3d> truth;  // T_j = T_w1⁻¹ T_wj, truth[0] = I
};

/// `count` frames of room_spheres at `width` x 3/4 width. Frame j is the scene's view moved by
/// j times a 3 cm / 1° camera motion; range noise "range:K" optional, drawn from `seed`.
inline JointTestWindow render_window(int count, int width, const std::string& noise = "none",
                                     std::uint64_t seed = 7,
                                     const std::string& scene_name = "room_spheres") {
  const SyntheticScene scene = load_scene(scene_name);
  JointTestWindow w;
  w.camera = synthetic_camera(width, width * 3 / 4);
  const Eigen::Isometry3d first = look_from(scene.view.eye, scene.view.target);
  const Vector6d motion =
      (Vector6d() << 0.025, -0.01, 0.012, 0.2 * M_PI / 180, 0.9 * M_PI / 180, -0.3 * M_PI / 180)
          .finished();
  for (int j = 0; j < count; ++j) {
    const Eigen::Isometry3d pose = first * se3_exp(j * motion);
    w.frames.push_back(render(scene, w.camera, pose, parse_noise(noise), seed, j));
    w.vertices.push_back(compute_vertex_map(w.frames.back().frame.depth, w.camera));
    w.truth.push_back(first.inverse() * pose);
  }
  w.truth[0] = Eigen::Isometry3d::Identity();
  return w;
}

/// The first `frames` frames of a walk through `scene_name` (jpcr_synth --trajectory walk) at
/// `width` x 3/4 width, with `noise` ("none", "range:K", "kinect") drawn from `seed`, which also
/// makes the walk.
inline SyntheticSequence walk(const std::string& scene_name, const std::string& noise,
                              std::uint64_t seed, int width, int frames = 2) {
  SyntheticSequenceOptions o;
  o.scene = scene_name;
  o.frames = frames;
  o.noise = noise;
  o.width = width;
  o.height = width * 3 / 4;
  o.seed = seed;
  return make_synthetic_sequence(o);
}

/// exp(δ) T with δ of `metres` translation and `degrees` rotation about fixed skew axes, the
/// sign alternating with `index` so the poses of a window are perturbed differently.
inline Eigen::Isometry3d perturbed(const Eigen::Isometry3d& T, double metres, double degrees,
                                   int index = 0) {
  const double s = index % 2 == 0 ? 1.0 : -1.0;
  const Eigen::Vector3d t = Eigen::Vector3d(1, -2, 2).normalized() * metres * s;
  const Eigen::Vector3d w = Eigen::Vector3d(-2, 1, 2).normalized() * degrees * M_PI / 180 * s;
  Vector6d xi;
  xi << t, w;
  return se3_exp(xi) * T;
}

/// T as the kernels' RigidMotion.
inline RigidMotion<double> motion(const Eigen::Isometry3d& T) {
  RigidMotion<double> m;
  m.R = T.linear();
  m.t = T.translation();
  return m;
}

struct PoseError {
  double translation = 0.0;  // m
  double rotation = 0.0;     // deg
};

inline PoseError pose_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d E = truth.inverse() * estimate;
  return {E.translation().norm(), rotation_angle(E.linear()) * 180.0 / M_PI};
}

/// The same pose to the last bit (a gauge or a pose left as given).
inline bool bitwise_equal(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return std::memcmp(a.matrix().data(), b.matrix().data(), 16 * sizeof(double)) == 0;
}

/// The same status at pixel (u, v) and, where valid, the same fit to the bit: quadric,
/// curvature and direction (an invalid pixel's curvature is NaN, so only its status counts).
inline bool same_fit(const QuadricMap& a, const QuadricMap& b, int u, int v) {
  if (a.status(u, v) != b.status(u, v)) return false;
  if (!a.valid(u, v)) return true;
  const Quadric &p = a.quadrics(u, v), &q = b.quadrics(u, v);
  return p.R == q.R && p.center == q.center && p.t_z == q.t_z && p.a == q.a && p.b == q.b &&
         p.c == q.c && a.curvature(u, v) == b.curvature(u, v) &&
         a.direction(u, v) == b.direction(u, v);
}

/// One line per refinement: verdict, steps, what took part, the cost history.
inline void print_report(const RefinementReport& r) {
  std::printf("%s: %s after %d steps (%d rejected), %d quadrics, %ld terms, cost", r.method.c_str(),
              to_string(r.verdict), r.iterations, r.rejected_steps, r.active_quadrics, r.terms);
  for (double c : r.cost)
    std::printf(" %.4g", c);
  std::printf("\n");
}

}  // namespace jpcr::test
