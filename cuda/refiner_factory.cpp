#include "jpcr/cuda/refiner_factory.hpp"

#include <utility>

#include "jpcr/cuda/cpu_fallback_refiner.hpp"

#if defined(JPCR_HAVE_CUDA)
#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/cuda_joint_ftf.hpp"
#endif

namespace jpcr {

std::unique_ptr<Refiner> make_refiner(const std::string& name, const JointParams& params,
                                      ComputeDevice device, std::ostream& log) {
  std::unique_ptr<Refiner> cpu = make_refiner(name, params);  // throws for an unknown name
  if (name != "j-ftf") {
    log << "jpcr: " << name << " has no GPU version; device " << to_string(device) << " -> cpu\n";
    return cpu;
  }
  // Without CUDA, resolve_device never returns kCuda (it throws for a cuda request).
  [[maybe_unused]] const ComputeDevice chosen = resolve_device(device, log);
#if defined(JPCR_HAVE_CUDA)
  if (chosen == ComputeDevice::kCuda) {
    try {
      auto gpu = std::make_unique<CudaJointFrameToFrame>(params);
      return std::make_unique<CpuFallbackRefiner>(std::move(gpu), std::move(cpu), log);
    } catch (const CudaError& e) {
      fall_back_to_cpu_or_rethrow(device, e, log);
    }
  }
#endif
  return cpu;
}

RefinerFactory device_refiner_factory(ComputeDevice device, std::ostream& log) {
  return [device, &log](const std::string& name, const JointParams& params,
                        const IcpBundleParams& bundle) -> std::unique_ptr<Refiner> {
    if (name == "j-ftf") return make_refiner(name, params, device, log);
    log << "jpcr: " << name << " runs on the cpu\n";
    return make_refiner(name, params, bundle);
  };
}

}  // namespace jpcr
