// Quad IT on the GPU (method.md §3; issue 7): one thread per pixel runs the reference kernel
// fit_quadric_pixel<double> (quadric/quadric_fit_kernel.hpp), the same code the CPU parity tests
// run on the host, and writes quadric, curvature, direction and status for every pixel; the
// initial normals, unless given, come from plane_normal on the device too. Same interface as
// QuadricFit. Plain C++ header; the CUDA side is in cuda_quadric_fit.cu.
//
// Device buffers are owned by the estimator, allocated for the first frame of a size and reused
// for every later frame of that size (no per-frame cudaMalloc). The pattern offsets travel as a
// __grid_constant__ kernel parameter, i.e. in the constant bank, read by all threads of a warp at
// once (a broadcast); patterns too large for a parameter fall back to global memory.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>

#include "jpcr/quadric/quadric_fit.hpp"

namespace jpcr {

/// Device times of the last estimate() call (CUDA events), in ms.
struct CudaQuadricFitTiming {
  float upload_ms = 0;    // vertices (and given normals) to the device
  float normals_ms = 0;   // the plane-normal kernel (0 when the normals were given)
  float kernel_ms = 0;    // the Quad IT kernel
  float download_ms = 0;  // the QuadricMap back to the host
  float total_ms = 0;     // first upload to last download
};

/// The floating-point type of the per-pixel fit. Double by default: float is faster but its
/// step-acceptance test flips at a few pixels per frame, ten times the 1e-4 1/m parity bound
/// (cuda/NOTES.md).
enum class CudaPrecision { kDouble, kFloat };

class CudaQuadricFit final : public CurvatureEstimator {
 public:
  /// Throws CudaError when no CUDA device is usable (check cuda_device_available() first).
  explicit CudaQuadricFit(const QuadricParams& params = {},
                          CudaPrecision precision = CudaPrecision::kDouble);
  ~CudaQuadricFit() override;
  CudaQuadricFit(const CudaQuadricFit&) = delete;
  CudaQuadricFit& operator=(const CudaQuadricFit&) = delete;

  /// Thread-safe (calls are serialised: they share the device buffers). Without `normals`, the
  /// initial normals are computed on the device by the same plane_normal as on the CPU.
  QuadricMap estimate(const VertexMap& vertices) const override;
  QuadricMap estimate(const VertexMap& vertices, const NormalMap& normals) const override;
  std::string name() const override { return "quad-it-cuda"; }
  CudaPrecision precision() const { return precision_; }
  const QuadricParams& params() const override { return params_; }

  CudaQuadricFitTiming last_timing() const;
  /// cudaMalloc calls so far (they happen for the first frame of each larger size only).
  std::size_t device_allocations() const;
  /// A check for tests: fill every device output and the host map with 0xFF bytes before each
  /// fit, so an element the kernel or the download forgot shows up as the sentinel.
  void set_poison_outputs(bool on);

 private:
  struct Device;
  QuadricMap fit(const VertexMap& vertices, const NormalMap* normals) const;

  QuadricParams params_;
  CudaPrecision precision_;
  std::unique_ptr<Device> device_;
  mutable std::mutex mutex_;
};

}  // namespace jpcr
