#include "jpcr/cuda/cuda_check.hpp"

#include <cstdlib>
#include <cstring>

#include <cuda_runtime_api.h>

namespace jpcr {

namespace {

[[noreturn]] void throw_cuda_error(cudaError_t error, const std::string& what, const char* file,
                                   int line) {
  throw CudaError("jpcr: CUDA " + what + " failed at " + file + ":" + std::to_string(line) + ": " +
                      cudaGetErrorName(error) + " (" + cudaGetErrorString(error) + ")",
                  error == cudaErrorMemoryAllocation);
}

}  // namespace

void cuda_check(int code, const char* call, const char* file, int line) {
  const cudaError_t error = static_cast<cudaError_t>(code);
  if (error != cudaSuccess) {
    cudaGetLastError();  // clear a non-sticky error so the next call starts clean
    throw_cuda_error(error, std::string("call ") + call, file, line);
  }
}

void cuda_check_launch(const char* kernel, CUstream_st* stream, const char* file, int line) {
  cudaError_t error = cudaGetLastError();
  if (error == cudaSuccess && cuda_synchronous_checks()) {
    error = cudaStreamSynchronize(stream);
    if (error != cudaSuccess) cudaGetLastError();  // not blamed on the next launch as well
  }
  // Without synchronous checks the error may be an earlier launch's, found only now.
  if (error != cudaSuccess)
    throw_cuda_error(error,
                     std::string("kernel ") + kernel +
                         (cuda_synchronous_checks() ? "" : " (or earlier work on its stream)"),
                     file, line);
}

bool cuda_synchronous_checks() {
#ifndef NDEBUG
  return true;
#else
  static const bool on = [] {
    const char* s = std::getenv("JPCR_CUDA_SYNC");
    return s != nullptr && std::strcmp(s, "1") == 0;
  }();
  return on;
#endif
}

}  // namespace jpcr
