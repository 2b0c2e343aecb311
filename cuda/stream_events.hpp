// A CUDA stream and N timing events owned together (RAII), for the .cu files of cuda/; this
// header includes the CUDA runtime, so only device-side translation units include it.
#pragma once

#include <cuda_runtime_api.h>

#include "jpcr/cuda/cuda_check.hpp"

namespace jpcr {

template <int N>
struct StreamEvents {
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
    for (cudaEvent_t& e : events)
      if (e != nullptr) cudaEventDestroy(e);
    if (stream != nullptr) cudaStreamDestroy(stream);
  }
};

}  // namespace jpcr
