#include "jpcr/cuda/cpu_fallback_estimator.hpp"

#include <utility>

namespace jpcr {

CpuFallbackEstimator::CpuFallbackEstimator(std::unique_ptr<CurvatureEstimator> gpu,
                                           std::unique_ptr<CurvatureEstimator> cpu,
                                           std::ostream& log)
    : gpu_(std::move(gpu)), cpu_(std::move(cpu)), fallback_(cpu_->name(), log) {}

QuadricMap CpuFallbackEstimator::estimate(const VertexMap& vertices) const {
  return fallback_.run([&] { return gpu_->estimate(vertices); },
                       [&] { return cpu_->estimate(vertices); });
}

QuadricMap CpuFallbackEstimator::estimate(const VertexMap& vertices,
                                          const NormalMap& normals) const {
  return fallback_.run([&] { return gpu_->estimate(vertices, normals); },
                       [&] { return cpu_->estimate(vertices, normals); });
}

}  // namespace jpcr
