#include "jpcr/cuda/device_selection.hpp"

#include <map>
#include <mutex>

#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/quadric/error.hpp"

#if defined(JPCR_HAVE_CUDA)
#include <cuda_runtime_api.h>
#endif

namespace jpcr {

namespace {

// What the runtime says about the calling thread's current device (device 0 unless the
// program chose another): the device a jpcr GPU object built in this thread runs on.
CudaDeviceInfo query_current_device() {
  CudaDeviceInfo info;
#if defined(JPCR_HAVE_CUDA)
  int count = 0;
  const cudaError_t error = cudaGetDeviceCount(&count);
  if (error != cudaSuccess) {
    cudaGetLastError();  // the failed query must not leak into later calls
    info.description = cudaGetErrorName(error);
    return info;
  }
  if (count < 1) {
    info.description = "cudaGetDeviceCount found 0 devices";
    return info;
  }
  int device = 0;
  cudaDeviceProp prop{};
  cudaError_t prop_error = cudaGetDevice(&device);
  if (prop_error == cudaSuccess) prop_error = cudaGetDeviceProperties(&prop, device);
  if (prop_error != cudaSuccess) {
    cudaGetLastError();
    info.description = cudaGetErrorName(prop_error);
    return info;
  }
  const std::string arch = "sm_" + std::to_string(prop.major) + std::to_string(prop.minor);
  const std::string which = device == 0 ? "" : " (device " + std::to_string(device) + ")";
  // The kernels are built for sm_75 and newer (nvcc 13 has nothing older).
  if (prop.major < 7 || (prop.major == 7 && prop.minor < 5)) {
    info.description = std::string(prop.name) + ", " + arch + which + " is older than sm_75";
    return info;
  }
  info.available = true;
  info.description = std::string(prop.name) + ", " + arch + which;
#else
  info.description = "built without CUDA";
#endif
  return info;
}

}  // namespace

ComputeDevice parse_compute_device(const std::string& text) {
  if (text == "auto") return ComputeDevice::kAuto;
  if (text == "cpu") return ComputeDevice::kCpu;
  if (text == "cuda") return ComputeDevice::kCuda;
  throw InputError("device: '" + text + "' is not one of auto, cpu, cuda");
}

std::string to_string(ComputeDevice device) {
  switch (device) {
    case ComputeDevice::kAuto:
      return "auto";
    case ComputeDevice::kCpu:
      return "cpu";
    case ComputeDevice::kCuda:
      return "cuda";
  }
  return "?";
}

const CudaDeviceInfo& query_cuda_device() {
#if defined(JPCR_HAVE_CUDA)
  int device = 0;
  if (cudaGetDevice(&device) != cudaSuccess) {
    cudaGetLastError();
    device = -1;  // no driver or no device: described by query_current_device
  }
#else
  const int device = -1;
#endif
  static std::mutex mutex;
  static std::map<int, CudaDeviceInfo> known;  // node-based: references stay valid
  const std::lock_guard<std::mutex> lock(mutex);
  const auto found = known.find(device);
  if (found != known.end()) return found->second;
  return known.emplace(device, query_current_device()).first->second;
}

bool cuda_device_available() {
  return query_cuda_device().available;
}

void fall_back_to_cpu_or_rethrow(ComputeDevice requested, const CudaError& e, std::ostream& log) {
  if (requested != ComputeDevice::kAuto) throw;
  log << "jpcr: device auto -> cpu (" << e.what() << ")\n";
}

ComputeDevice resolve_device(ComputeDevice requested, std::ostream& log) {
  const CudaDeviceInfo& gpu = query_cuda_device();
  ComputeDevice chosen = requested;
  std::string why;
  switch (requested) {
    case ComputeDevice::kCpu:
      why = "requested";
      break;
    case ComputeDevice::kCuda:
      if (!gpu.available)
        throw CudaError("jpcr: device cuda was requested but no CUDA device is usable (" +
                        gpu.description + "); use device: auto or cpu");
      why = gpu.description;
      break;
    case ComputeDevice::kAuto:
      chosen = gpu.available ? ComputeDevice::kCuda : ComputeDevice::kCpu;
      why = gpu.available ? gpu.description : "no CUDA device: " + gpu.description;
      break;
  }
  log << "jpcr: device " << to_string(requested) << " -> " << to_string(chosen) << " (" << why
      << ")\n";
  return chosen;
}

}  // namespace jpcr
