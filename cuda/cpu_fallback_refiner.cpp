#include "jpcr/cuda/cpu_fallback_refiner.hpp"

#include <utility>

namespace jpcr {

CpuFallbackRefiner::CpuFallbackRefiner(std::unique_ptr<Refiner> gpu, std::unique_ptr<Refiner> cpu,
                                       std::ostream& log)
    : gpu_(std::move(gpu)), cpu_(std::move(cpu)), fallback_(gpu_->name(), log) {}

RefinementResult CpuFallbackRefiner::refine(const std::vector<VertexMap>& vertices,
                                            const CameraIntrinsics& camera,
                                            const std::vector<Eigen::Isometry3d>& initial_poses,
                                            const QuadricMap& initial_quadrics) const {
  return fallback_.run(
      [&] { return gpu_->refine(vertices, camera, initial_poses, initial_quadrics); },
      [&] { return cpu_->refine(vertices, camera, initial_poses, initial_quadrics); });
}

}  // namespace jpcr
