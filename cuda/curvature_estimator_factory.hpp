// The Quad IT estimator for a `device:` setting: QuadricFit on the CPU or CudaQuadricFit on the
// GPU, behind the one CurvatureEstimator interface (issue 7). Works in every build profile.
#pragma once

#include <memory>
#include <ostream>

#include "jpcr/cuda/device_selection.hpp"
#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {

/// Resolves `device` (one line on `log`, device_selection.hpp) and builds the Quad IT estimator.
/// The GPU one comes in a CpuFallbackEstimator: a device failure mid-run moves frames to the
/// CPU (cpu_fallback.hpp); `log` must outlive the estimator.
std::unique_ptr<CurvatureEstimator> make_curvature_estimator(ComputeDevice device,
                                                             const QuadricParams& params,
                                                             std::ostream& log);

}  // namespace jpcr
