#include "jpcr/cuda/cpu_fallback_refiner.hpp"

#include <utility>

#include "jpcr/cuda/cuda_check.hpp"

namespace jpcr {

CpuFallbackRefiner::CpuFallbackRefiner(std::unique_ptr<Refiner> gpu, std::unique_ptr<Refiner> cpu,
                                       std::ostream& log)
    : gpu_(std::move(gpu)), cpu_(std::move(cpu)), log_(log) {}

RefinementResult CpuFallbackRefiner::refine(const std::vector<VertexMap>& vertices,
                                            const CameraIntrinsics& camera,
                                            const std::vector<Eigen::Isometry3d>& initial_poses,
                                            const QuadricMap& initial_quadrics) const {
  if (!failed_) {
    try {
      return gpu_->refine(vertices, camera, initial_poses, initial_quadrics);
    } catch (const CudaError& e) {
      failed_ = true;
      std::call_once(logged_, [&] {
        log_ << "jpcr: " << gpu_->name() << " on the GPU failed (" << e.what()
             << "); it runs on the cpu from here on\n";
      });
    }
  }
  return cpu_->refine(vertices, camera, initial_poses, initial_quadrics);
}

}  // namespace jpcr
