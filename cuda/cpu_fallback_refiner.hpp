// A GPU refiner with the CPU one behind it: a CudaError from the GPU (a kernel fault leaves the
// CUDA context unusable for the whole process; out of memory on a larger frame) sends that
// refinement, and every later one, to the CPU, with one line on the log. Without it every later
// pair would end in the `error` verdict and keep the front end's poses. Bad input
// (std::invalid_argument) is the caller's and passes through.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

#include "jpcr/backend/refiner.hpp"

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
  /// True once a GPU failure sent the refinements to the CPU.
  bool on_cpu() const { return failed_; }

 private:
  std::unique_ptr<Refiner> gpu_, cpu_;
  std::ostream& log_;
  mutable std::atomic<bool> failed_{false};
  mutable std::once_flag logged_;
};

}  // namespace jpcr
