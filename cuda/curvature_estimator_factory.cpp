#include "jpcr/cuda/curvature_estimator_factory.hpp"

#include "jpcr/cuda/cpu_fallback_estimator.hpp"

#if defined(JPCR_HAVE_CUDA)
#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/cuda_quadric_fit.hpp"
#endif

namespace jpcr {

std::unique_ptr<CurvatureEstimator> make_curvature_estimator(ComputeDevice device,
                                                             const QuadricParams& params,
                                                             std::ostream& log) {
  // Without CUDA, resolve_device never returns kCuda (it throws for a cuda request).
  [[maybe_unused]] const ComputeDevice chosen = resolve_device(device, log);
#if defined(JPCR_HAVE_CUDA)
  if (chosen == ComputeDevice::kCuda) {
    try {
      return std::make_unique<CpuFallbackEstimator>(std::make_unique<CudaQuadricFit>(params),
                                                    std::make_unique<QuadricFit>(params), log);
    } catch (const CudaError& e) {
      fall_back_to_cpu_or_rethrow(device, e, log);
    }
  }
#endif
  return std::make_unique<QuadricFit>(params);
}

}  // namespace jpcr
