// The window the joint benchmarks time (bench_joint on the CPU, bench_cuda_joint on the GPU):
// the back-end benchmark window (bench_windows.hpp) with Quad IT quadrics on the reference frame.
#pragma once

#include <vector>

#include "bench_windows.hpp"
#include "jpcr/backend/joint_system.hpp"
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
  BenchWindow b = make_bench_window(width, frames);
  JointBenchWindow w;
  w.camera = b.camera;
  w.vertices = std::move(b.vertices);
  w.state.poses = std::move(b.start);
  w.initial = QuadricFit(quadric).estimate(w.vertices[0]);
  for (std::size_t i = 0; i < w.initial.status.size(); ++i) {
    w.state.quadrics.push_back(w.initial.quadrics[i].cast<double>());
    w.state.valid.push_back(w.initial.status[i] == QuadricStatus::kValid ? 1 : 0);
  }
  return w;
}

}  // namespace jpcr::bench
