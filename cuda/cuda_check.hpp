// Error checking for every CUDA runtime call (issue 7): JPCR_CUDA_CHECK(cudaMalloc(...)) throws
// jpcr::CudaError naming the call, file, line and cudaGetErrorString. Plain C++: the error code
// travels as an int, so this header includes no CUDA header.
#pragma once

#include <stdexcept>
#include <string>

struct CUstream_st;  // cudaStream_t is CUstream_st*

namespace jpcr {

/// A failed CUDA call or kernel launch, or a CUDA device that was asked for and is not there.
/// out_of_memory(): a cudaMalloc the device could not serve. That error is not sticky: the
/// context stays usable, and a later call with less memory in use may succeed. Every other
/// failure is treated as the loss of the device for the process (a kernel fault is sticky).
class CudaError : public std::runtime_error {
 public:
  explicit CudaError(const std::string& what, bool out_of_memory = false)
      : std::runtime_error(what), out_of_memory_(out_of_memory) {}
  bool out_of_memory() const { return out_of_memory_; }

 private:
  bool out_of_memory_;
};

/// Throws CudaError unless `code` (a cudaError_t) is cudaSuccess.
void cuda_check(int code, const char* call, const char* file, int line);

/// After a kernel launch on `stream`: the launch error (cudaGetLastError) and, when synchronous
/// checking is on, the kernel's own error (cudaStreamSynchronize: this stream only, so another
/// thread's work on the device neither waits nor is blamed). The runtime keeps the last error per
/// thread: an error of the caller's own CUDA work that its thread left unread is reported here as
/// the launch's (and read).
void cuda_check_launch(const char* kernel, CUstream_st* stream, const char* file, int line);

/// Synchronous checking: on in debug builds (no NDEBUG) and when JPCR_CUDA_SYNC=1 (the GPU
/// tests set it), so a faulting kernel is reported at its launch.
bool cuda_synchronous_checks();

}  // namespace jpcr

#define JPCR_CUDA_CHECK(expr) ::jpcr::cuda_check(static_cast<int>(expr), #expr, __FILE__, __LINE__)
#define JPCR_CUDA_CHECK_LAUNCH(kernel, stream) \
  ::jpcr::cuda_check_launch(kernel, stream, __FILE__, __LINE__)
