// The GPU Quad IT with the CPU one behind it (CpuFallback, cpu_fallback.hpp): a device failure
// mid-run sends the frame to the CPU instead of ending the run; out of device memory that one
// frame, any other failure every later frame too.
#pragma once

#include <memory>
#include <ostream>
#include <string>

#include "jpcr/cuda/cpu_fallback.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {

class CpuFallbackEstimator final : public CurvatureEstimator {
 public:
  /// `gpu` and `cpu` run the same method with the same parameters; `log` must outlive this.
  CpuFallbackEstimator(std::unique_ptr<CurvatureEstimator> gpu,
                       std::unique_ptr<CurvatureEstimator> cpu, std::ostream& log);
  QuadricMap estimate(const VertexMap& vertices) const override;
  QuadricMap estimate(const VertexMap& vertices, const NormalMap& normals) const override;
  std::string name() const override { return gpu_->name(); }
  const QuadricParams& params() const override { return gpu_->params(); }
  /// True once a GPU failure sent every later frame to the CPU.
  bool on_cpu() const { return fallback_.on_cpu(); }
  /// Frames that ran on the CPU because the device was out of memory.
  int out_of_memory_calls() const { return fallback_.out_of_memory_calls(); }
  /// Frames that ran on the CPU, for any reason, and the name of what ran them.
  int cpu_calls() const { return fallback_.cpu_calls(); }
  std::string cpu_name() const { return cpu_->name(); }

 private:
  std::unique_ptr<CurvatureEstimator> gpu_, cpu_;
  CpuFallback fallback_;
};

}  // namespace jpcr
