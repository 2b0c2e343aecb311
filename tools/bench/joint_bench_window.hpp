// The window the joint benchmarks time (bench_joint on the CPU, bench_cuda_joint on the GPU):
// room_spheres with range:1 noise, Quad IT quadrics on the reference frame, the poses 1 cm / 1°
// off the truth.
#pragma once

#include <vector>

#include "jpcr/backend/joint_system.hpp"
#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr::bench {

struct JointBenchWindow {
  CameraIntrinsics camera;
  std::vector<VertexMap> vertices;
  JointState state;
  QuadricMap initial;  // Quad IT on vertices[0]
};

/// `frames` frames at width x 3/4 width; Quad IT with `quadric` (its pattern decides the sizes).
inline JointBenchWindow make_joint_window(int width, int frames,
                                          const QuadricParams& quadric = {}) {
  SyntheticSequenceOptions options;
  options.frames = frames;
  options.noise = "range:1";
  options.width = width;
  options.height = width * 3 / 4;
  const SyntheticSequence seq = make_synthetic_sequence(options);
  JointBenchWindow w;
  w.camera = seq.camera();
  const Eigen::Isometry3d first = *seq.ground_truth(0);
  Vector6d offset;
  offset << 0.006, -0.006, 0.006, 0.01, -0.01, 0.01;  // ≈ 1 cm, 1°
  for (int j = 0; j < frames; ++j) {
    const Frame f = seq.load(static_cast<std::size_t>(j));
    w.vertices.push_back(compute_vertex_map(f.depth, w.camera));
    const Eigen::Isometry3d T = first.inverse() * *seq.ground_truth(static_cast<std::size_t>(j));
    w.state.poses.push_back(j == 0 ? Eigen::Isometry3d::Identity() : se3_exp(offset) * T);
  }
  w.initial = QuadricFit(quadric).estimate(w.vertices[0]);
  for (std::size_t i = 0; i < w.initial.status.size(); ++i) {
    w.state.quadrics.push_back(w.initial.quadrics[i].cast<double>());
    w.state.valid.push_back(w.initial.status[i] == QuadricStatus::kValid ? 1 : 0);
  }
  return w;
}

}  // namespace jpcr::bench
