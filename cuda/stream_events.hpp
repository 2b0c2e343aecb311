// A CUDA stream and N timing events owned together (RAII), and the scope that makes their
// device current, for the .cu files of cuda/; this header includes the CUDA runtime, so only
// device-side translation units include it.
#pragma once

#include <exception>
#include <new>

#include <cuda_runtime_api.h>

#include "jpcr/cuda/cuda_check.hpp"

namespace jpcr {

/// Makes `device` current in the calling thread for a scope and gives the caller's device back
/// after it. A jpcr GPU object keeps the device that was current when it was built, and an
/// embedder's thread may call it with another one current: a launch into another device's
/// stream fails, and a kernel on another device's memory faults the whole context.
class DeviceScope {
 public:
  /// Throws CudaError when the current device cannot be read or `device` made current.
  explicit DeviceScope(int device) {
    JPCR_CUDA_CHECK(cudaGetDevice(&previous_));
    if (previous_ != device) {
      JPCR_CUDA_CHECK(cudaSetDevice(device));
      switched_ = true;
    }
  }
  /// For destructors: on a failure the current device stays as it is.
  DeviceScope(int device, std::nothrow_t) noexcept {
    if (cudaGetDevice(&previous_) != cudaSuccess) {
      cudaGetLastError();
      return;
    }
    if (previous_ == device) return;
    switched_ = cudaSetDevice(device) == cudaSuccess;
    if (!switched_) cudaGetLastError();  // the failed switch's error; none is cleared otherwise
  }
  ~DeviceScope() {
    if (switched_ && cudaSetDevice(previous_) != cudaSuccess) cudaGetLastError();
  }
  DeviceScope(const DeviceScope&) = delete;
  DeviceScope& operator=(const DeviceScope&) = delete;

  /// The calling thread's current device.
  static int current() {
    int device = 0;
    JPCR_CUDA_CHECK(cudaGetDevice(&device));
    return device;
  }

 private:
  int previous_ = 0;
  bool switched_ = false;
};

/// Waits for `stream` when the scope is left by an exception: the copies and kernels already
/// queued there must not outlive the buffers that unwinding frees. Errors are not reported (the
/// exception in flight is).
class DrainOnUnwind {
 public:
  explicit DrainOnUnwind(cudaStream_t stream) : stream_(stream) {}
  ~DrainOnUnwind() {
    if (std::uncaught_exceptions() > exceptions_ && cudaStreamSynchronize(stream_) != cudaSuccess)
      cudaGetLastError();
  }
  DrainOnUnwind(const DrainOnUnwind&) = delete;
  DrainOnUnwind& operator=(const DrainOnUnwind&) = delete;

 private:
  cudaStream_t stream_;
  int exceptions_ = std::uncaught_exceptions();
};

template <int N>
struct StreamEvents {
  const int device = DeviceScope::current();  // the stream's device, current when it was made
  cudaStream_t stream = nullptr;  // non-blocking: no implicit sync with the legacy stream
  cudaEvent_t events[N] = {};

  StreamEvents() {
    try {
      JPCR_CUDA_CHECK(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
      for (cudaEvent_t& e : events)
        JPCR_CUDA_CHECK(cudaEventCreate(&e));
    } catch (...) {
      destroy();
      throw;
    }
  }
  ~StreamEvents() { destroy(); }
  StreamEvents(const StreamEvents&) = delete;
  StreamEvents& operator=(const StreamEvents&) = delete;

  void record(int event) { JPCR_CUDA_CHECK(cudaEventRecord(events[event], stream)); }

  /// Milliseconds between two recorded events (after they completed).
  float elapsed_ms(int from, int to) const {
    float ms = 0.0f;
    JPCR_CUDA_CHECK(cudaEventElapsedTime(&ms, events[from], events[to]));
    return ms;
  }

 private:
  void destroy() noexcept {
    const DeviceScope scope(device, std::nothrow);
    // A failure is cleared here, so that no later launch check is blamed for it.
    for (cudaEvent_t& e : events)
      if (e != nullptr && cudaEventDestroy(e) != cudaSuccess) cudaGetLastError();
    if (stream != nullptr && cudaStreamDestroy(stream) != cudaSuccess) cudaGetLastError();
  }
};

}  // namespace jpcr
