// The switch behind CpuFallbackRefiner and CpuFallbackEstimator: a call runs on the GPU, and on a
// CudaError the same call runs on the CPU, so a run keeps its results when the device fails.
//  - Out of device memory (CudaError::out_of_memory, not sticky) sends only that call to the
//    CPU: memory another process held may be free for the next one. After
//    kMaxOutOfMemoryInARow of them in a row every later call runs on the CPU.
//  - Any other CUDA failure (a kernel fault leaves the context unusable for the process) sends
//    that call and every later one to the CPU.
// One log line for the first out-of-memory and one for the switch for good. Bad input
// (std::invalid_argument and the like) is the caller's and passes through.
#pragma once

#include <atomic>
#include <mutex>
#include <ostream>
#include <string>
#include <utility>

#include "jpcr/cuda/cuda_check.hpp"

namespace jpcr {

class CpuFallback {
 public:
  static constexpr int kMaxOutOfMemoryInARow = 3;

  /// `method` names the work in the log ("j-ftf"); `log` must outlive the switch.
  CpuFallback(std::string method, std::ostream& log) : method_(std::move(method)), log_(log) {}

  /// gpu() unless the switch is on the CPU for good, cpu() when it is or when gpu() throws a
  /// CudaError. Both return the same type.
  template <typename Gpu, typename Cpu>
  auto run(const Gpu& gpu, const Cpu& cpu) const {
    if (!on_cpu_) {
      try {
        auto result = gpu();
        out_of_memory_in_a_row_ = 0;
        return result;
      } catch (const CudaError& e) {
        record(e);
      }
    }
    ++cpu_calls_;
    return cpu();
  }

  /// True once every call runs on the CPU.
  bool on_cpu() const { return on_cpu_; }
  /// Calls that ran on the CPU because the device was out of memory.
  int out_of_memory_calls() const { return out_of_memory_calls_; }
  /// Calls that ran on the CPU, for any reason.
  int cpu_calls() const { return cpu_calls_; }

 private:
  void record(const CudaError& e) const;

  std::string method_;
  std::ostream& log_;
  mutable std::mutex mutex_;  // the log and the decision to switch
  mutable std::atomic<bool> on_cpu_{false};
  mutable std::atomic<int> out_of_memory_in_a_row_{0}, out_of_memory_calls_{0}, cpu_calls_{0};
};

}  // namespace jpcr
