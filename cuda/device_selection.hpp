// Which processor runs the per-pixel work (issue 7, config key `device: auto | cpu | cuda`):
// `auto` takes the GPU when cudaGetDeviceCount finds one and the CPU otherwise, and says which in
// one log line. Built in every profile; without CUDA no device is ever available.
#pragma once

#include <ostream>
#include <string>

namespace jpcr {

enum class ComputeDevice { kAuto, kCpu, kCuda };

/// Parses "auto", "cpu" or "cuda"; throws InputError naming the allowed values otherwise.
ComputeDevice parse_compute_device(const std::string& text);
std::string to_string(ComputeDevice device);

/// What cudaGetDeviceCount and cudaGetDeviceProperties say about the calling thread's current
/// device (device 0 unless the program chose another with cudaSetDevice): the device a jpcr GPU
/// object built in that thread keeps using, whichever device is current when it is called.
struct CudaDeviceInfo {
  bool available = false;
  /// "NVIDIA H100 80GB HBM3, sm_90" when available; otherwise why not, e.g. "cudaErrorNoDevice"
  /// or "built without CUDA".
  std::string description;
};

/// Queried once per process and device. Errors (no driver: 35, no device: 100, ...) mean "no
/// GPU", never a throw.
const CudaDeviceInfo& query_cuda_device();
bool cuda_device_available();

/// The device to use for `requested`, with exactly one line on `log`, e.g.
///   jpcr: device auto -> cpu (no CUDA device: cudaErrorNoDevice)
///   jpcr: device auto -> cuda (NVIDIA H100 80GB HBM3, sm_90)
/// Never returns kAuto. Requesting kCuda without a usable GPU throws CudaError saying why.
ComputeDevice resolve_device(ComputeDevice requested, std::ostream& log);

class CudaError;

/// Called from a `catch (const CudaError& e)` around building a GPU object (the CUDA context and
/// stream come first there: a GPU in exclusive-process mode held by another process, out of
/// memory, an unusable MIG slice): for `requested` kAuto logs
///   jpcr: device auto -> cpu (<e.what()>)
/// and returns, so that the caller builds the CPU object; otherwise rethrows.
void fall_back_to_cpu_or_rethrow(ComputeDevice requested, const CudaError& e, std::ostream& log);

}  // namespace jpcr
