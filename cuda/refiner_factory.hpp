// The refiner for a method name and a `device:` setting (issue 7): J-ftf runs on the GPU
// (CudaJointFrameToFrame) when the device resolves to cuda and on the CPU otherwise; J-full and
// Q-full have no GPU version and always run on the CPU. Works in every build profile.
#pragma once

#include <memory>
#include <ostream>
#include <string>

#include "jpcr/backend/refiner.hpp"
#include "jpcr/cuda/device_selection.hpp"

namespace jpcr {

/// As make_refiner(name, params) (refiner.hpp), with one line on `log` saying where it runs.
/// Throws InputError for an unknown name and CudaError when cuda is requested for j-ftf
/// without a usable GPU. The GPU J-ftf comes in a CpuFallbackRefiner: a device failure during a
/// run sends refinements to the CPU (cpu_fallback.hpp; one more line on `log`).
std::unique_ptr<Refiner> make_refiner(const std::string& name, const JointParams& params,
                                      ComputeDevice device, std::ostream& log);

/// The pipeline's refiners for a `device:` setting (PipelineBackEnd, KeyframePipeline): J-ftf
/// through make_refiner above, the others on the CPU with their own parameters. Each refiner
/// made writes its line on `log`, which must outlive the factory's use.
RefinerFactory device_refiner_factory(ComputeDevice device, std::ostream& log);

}  // namespace jpcr
