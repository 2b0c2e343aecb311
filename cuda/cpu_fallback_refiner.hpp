// A GPU refiner with the CPU one behind it (CpuFallback, cpu_fallback.hpp): a device failure
// sends the refinement to the CPU instead of ending it in the `error` verdict with the front
// end's poses; out of device memory that one refinement, any other failure every later one too.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "jpcr/backend/refiner.hpp"
#include "jpcr/cuda/cpu_fallback.hpp"

namespace jpcr {

class CpuFallbackRefiner final : public Refiner {
 public:
  /// `gpu` and `cpu` run the same method; `log` must outlive the refiner.
  CpuFallbackRefiner(std::unique_ptr<Refiner> gpu, std::unique_ptr<Refiner> cpu, std::ostream& log);
  using Refiner::refine;
  RefinementResult refine(const std::vector<VertexMap>& vertices, const CameraIntrinsics& camera,
                          const std::vector<Eigen::Isometry3d>& initial_poses,
                          const QuadricMap& initial_quadrics) const override;
  std::string name() const override { return gpu_->name(); }
  const JointParams& params() const override { return gpu_->params(); }
  bool refines_quadrics() const override { return gpu_->refines_quadrics(); }
  /// True once a GPU failure sent every later refinement to the CPU.
  bool on_cpu() const { return fallback_.on_cpu(); }
  /// Refinements that ran on the CPU because the device was out of memory.
  int out_of_memory_calls() const { return fallback_.out_of_memory_calls(); }

 private:
  std::unique_ptr<Refiner> gpu_, cpu_;
  CpuFallback fallback_;
};

}  // namespace jpcr
