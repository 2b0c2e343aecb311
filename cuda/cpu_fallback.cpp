#include "jpcr/cuda/cpu_fallback.hpp"

namespace jpcr {

void CpuFallback::record(const CudaError& e) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (e.out_of_memory()) ++out_of_memory_calls_;
  if (on_cpu_) return;  // another thread's failure switched it already
  if (!e.out_of_memory()) {
    on_cpu_ = true;
    log_ << "jpcr: " << method_ << " on the GPU failed (" << e.what()
         << "); it runs on the cpu from here on\n";
    return;
  }
  if (++out_of_memory_in_a_row_ >= kMaxOutOfMemoryInARow) {
    on_cpu_ = true;
    log_ << "jpcr: " << method_ << " on the GPU ran out of device memory " << kMaxOutOfMemoryInARow
         << " times in a row; it runs on the cpu from here on\n";
  } else if (out_of_memory_calls_ == 1) {
    log_ << "jpcr: " << method_ << " on the GPU ran out of device memory (" << e.what()
         << "); this call runs on the cpu and the next tries the GPU again\n";
  }
}

}  // namespace jpcr
