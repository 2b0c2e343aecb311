// The window the back-end benchmarks refine: `frames` frames of room_spheres (walk) with range:1
// noise at `width` x 3/4 width, their vertex maps, and start poses T_1 = I, T_j 1 cm / 1° off the
// truth (frame j → frame 1).
#pragma once

#include <vector>

#include "jpcr/io/synthetic_sequence.hpp"
#include "jpcr/quadric/se3.hpp"

namespace jpcr::bench {

struct BenchWindow {
  CameraIntrinsics camera;
  std::vector<VertexMap> vertices;
  std::vector<Eigen::Isometry3d> start;
};

inline BenchWindow make_bench_window(int width, int frames) {
  SyntheticSequenceOptions options;
  options.frames = frames;
  options.noise = "range:1";
  options.width = width;
  options.height = width * 3 / 4;
  const SyntheticSequence seq = make_synthetic_sequence(options);
  BenchWindow w;
  w.camera = seq.camera();
  const Eigen::Isometry3d first = *seq.ground_truth(0);
  Vector6d offset;
  offset << 0.006, -0.006, 0.006, 0.01, -0.01, 0.01;  // ≈ 1 cm, 1°
  for (int j = 0; j < frames; ++j) {
    const auto index = static_cast<std::size_t>(j);
    w.vertices.push_back(compute_vertex_map(seq.load(index).depth, w.camera));
    const Eigen::Isometry3d T = first.inverse() * *seq.ground_truth(index);
    w.start.push_back(j == 0 ? Eigen::Isometry3d::Identity() : se3_exp(offset) * T);
  }
  return w;
}

}  // namespace jpcr::bench
