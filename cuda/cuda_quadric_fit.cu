// Quad IT on the GPU: one thread per pixel calls fit_quadric_pixel<Scalar>, the reference kernel
// of method.md §3 shared with the CPU (quadric/quadric_fit_kernel.hpp).
//
// Scalar is double by default (cuda/NOTES.md, tests/cuda/test_kernel_precision.cpp): float sums
// are accurate (about 1e-6 1/m RMS where float and double take the same steps), but at about
// 0.03 % of the pixels of a noisy frame the float cost test keeps or undoes a step the double one
// does not, which moves κ by up to 1 1/m and the map RMS to 1e-3 1/m, ten times the 1e-4 bound.
// Double on the GPU against double on the host differs by 1e-14 1/m (FMA contraction only).
#include "jpcr/cuda/cuda_quadric_fit.hpp"

#include <cstring>
#include <limits>
#include <stdexcept>

#include <cuda_runtime.h>

#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/device_memory.hpp"
#include "jpcr/cuda/stream_events.hpp"
#include "jpcr/quadric/plane_normal_kernel.hpp"
#include "jpcr/quadric/quadric_fit_kernel.hpp"

namespace jpcr {

namespace {

// 32x8 threads: a warp covers 32 consecutive pixels of one row, so for each pattern offset its
// vertex loads are one contiguous 384-byte run (coalesced) and every lane reads the same offset.
constexpr int kBlockWidth = 32;
constexpr int kBlockHeight = 8;

// The largest pattern passed as a kernel parameter (the constant bank): 480 offsets of 8 bytes
// stay under the classic 4 KB parameter limit. The reference pattern has 129.
constexpr int kParameterPatternCapacity = 480;

struct ParameterPattern {
  PixelOffset offsets[kParameterPatternCapacity];
  int size;
};

// The four images of a QuadricMap on the device.
struct QuadricMapView {
  Quadric* quadrics;
  Eigen::Vector2f* curvature;
  Eigen::Vector3f* direction;
  QuadricStatus* status;
};

// Quad IT at (u, v); the outputs are stored as QuadricMap::set and set_invalid store them on the
// CPU (quadric_map.cpp): the float quadric, its curvature and direction; a non-finite curvature
// turns the pixel into kSingular.
template <typename Scalar>
__device__ __forceinline__ void fit_and_store(const PixelOffset* pattern, int pattern_size,
                                              const VertexView& vertices,
                                              const Eigen::Vector3f* __restrict__ normals,
                                              const QuadricFitParams& params,
                                              const QuadricMapView& out, int u, int v) {
  const int i = v * vertices.width + u;
  const Eigen::Vector3f normal = normals[i];
  QuadricT<Scalar> fitted;
  QuadricStatus status =
      fit_quadric_pixel<Scalar>(vertices, pattern, pattern_size, u, v, normal, params, fitted);
  const Quadric q = fitted.template cast<float>();
  Eigen::Vector2f kappa;
  if (status == QuadricStatus::kValid) {
    kappa = principal_curvatures(q.a, q.b, q.c);
    if (!is_finite_value(kappa.x()) || !is_finite_value(kappa.y()))
      status = QuadricStatus::kSingular;
  }
  if (status == QuadricStatus::kValid) {
    out.quadrics[i] = q;
    out.curvature[i] = kappa;
    out.direction[i] = principal_direction(q);
  } else {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    out.quadrics[i] = Quadric{};
    out.curvature[i] = Eigen::Vector2f(nan, nan);
    out.direction[i] = Eigen::Vector3f(nan, nan, nan);
  }
  out.status[i] = status;
}

// The initial normals (method.md §3), as estimate_normals computes them on the CPU.
__global__ void __launch_bounds__(kBlockWidth* kBlockHeight)
    plane_normals(VertexView vertices, NormalEstimationParams params,
                  Eigen::Vector3f* __restrict__ normals) {
  const int u = blockIdx.x * kBlockWidth + threadIdx.x;
  const int v = blockIdx.y * kBlockHeight + threadIdx.y;
  if (u >= vertices.width || v >= vertices.height) return;
  normals[v * vertices.width + u] = plane_normal(vertices, u, v, params);
}

dim3 grid_for(const VertexView& view) {
  return dim3((view.width + kBlockWidth - 1) / kBlockWidth,
              (view.height + kBlockHeight - 1) / kBlockHeight);
}

// Blocks per SM that the register budget must allow (ptxas caps the registers at
// 65536 / (256 · this)). 1 gives the double kernel its 211 registers and no spills, but only 8
// warps per SM; 2 caps it at 128 registers with 0.4 KB of spills per thread (to L1) and 16 warps.
// On the H200 (2026-12-04, 640x480, median of 30): 1.71 ms with 1, 1.22 ms with 2 (float, 120
// registers either way: 0.80 / 0.82 ms). Settable for measuring (-DJPCR_QUAD_IT_MIN_BLOCKS=N).
#ifndef JPCR_QUAD_IT_MIN_BLOCKS
#define JPCR_QUAD_IT_MIN_BLOCKS 2
#endif

template <typename Scalar>
__global__ void __launch_bounds__(kBlockWidth* kBlockHeight, JPCR_QUAD_IT_MIN_BLOCKS)
    quad_it_parameter_pattern(const __grid_constant__ ParameterPattern pattern, VertexView vertices,
                              const Eigen::Vector3f* __restrict__ normals, QuadricFitParams params,
                              QuadricMapView out) {
  const int u = blockIdx.x * kBlockWidth + threadIdx.x;
  const int v = blockIdx.y * kBlockHeight + threadIdx.y;
  if (u >= vertices.width || v >= vertices.height) return;
  fit_and_store<Scalar>(pattern.offsets, pattern.size, vertices, normals, params, out, u, v);
}

template <typename Scalar>
__global__ void __launch_bounds__(kBlockWidth* kBlockHeight)
    quad_it_global_pattern(const PixelOffset* __restrict__ pattern, int pattern_size,
                           VertexView vertices, const Eigen::Vector3f* __restrict__ normals,
                           QuadricFitParams params, QuadricMapView out) {
  const int u = blockIdx.x * kBlockWidth + threadIdx.x;
  const int v = blockIdx.y * kBlockHeight + threadIdx.y;
  if (u >= vertices.width || v >= vertices.height) return;
  fit_and_store<Scalar>(pattern, pattern_size, vertices, normals, params, out, u, v);
}

// The kernel for the pattern: offsets in the parameter bank when they fit, else in d.pattern.
template <typename Scalar>
void launch_quad_it(const NeighbourhoodPattern& pattern, const DeviceArray<PixelOffset>& global,
                    const VertexView& view, const Eigen::Vector3f* normals,
                    const QuadricFitParams& params, const QuadricMapView& out,
                    cudaStream_t stream) {
  const dim3 block(kBlockWidth, kBlockHeight);
  const dim3 grid = grid_for(view);
  const int size = pattern.size();
  if (size <= kParameterPatternCapacity) {
    ParameterPattern p{};
    for (int k = 0; k < size; ++k)
      p.offsets[k] = pattern.offsets[k];
    p.size = size;
    quad_it_parameter_pattern<Scalar><<<grid, block, 0, stream>>>(p, view, normals, params, out);
    JPCR_CUDA_CHECK_LAUNCH("quad_it_parameter_pattern", stream);
  } else {
    quad_it_global_pattern<Scalar>
        <<<grid, block, 0, stream>>>(global.data(), size, view, normals, params, out);
    JPCR_CUDA_CHECK_LAUNCH("quad_it_global_pattern", stream);
  }
}

template <typename T>
void upload(DeviceArray<T>& to, const T* from, std::size_t count, cudaStream_t stream) {
  JPCR_CUDA_CHECK(
      cudaMemcpyAsync(to.data(), from, count * sizeof(T), cudaMemcpyHostToDevice, stream));
}

template <typename T>
void download(T* to, const DeviceArray<T>& from, std::size_t count, cudaStream_t stream) {
  JPCR_CUDA_CHECK(
      cudaMemcpyAsync(to, from.data(), count * sizeof(T), cudaMemcpyDeviceToHost, stream));
}

template <typename T>
void poison(DeviceArray<T>& a, std::size_t count, cudaStream_t stream) {
  JPCR_CUDA_CHECK(cudaMemsetAsync(a.data(), 0xFF, count * sizeof(T), stream));
}

template <typename T>
void poison(Image<T>& image) {
  std::memset(static_cast<void*>(image.data()), 0xFF, image.size() * sizeof(T));
}

}  // namespace

// The stream, the timing events and the buffers, sized for the largest frame seen so far.
struct CudaQuadricFit::Device : StreamEvents<5> {  // start, uploaded, normals, fitted, downloaded
  DeviceArray<Eigen::Vector3f> vertices, normals, direction;
  DeviceArray<Quadric> quadrics;
  DeviceArray<Eigen::Vector2f> curvature;
  DeviceArray<QuadricStatus> status;
  DeviceArray<PixelOffset> pattern;  // only for patterns beyond kParameterPatternCapacity
  std::size_t allocations = 0;
  bool poison_outputs = false;
  CudaQuadricFitTiming timing;

  // One at a time, so that the allocations made before one that throws are counted.
  void reserve(std::size_t pixels, std::size_t pattern_size) {
    allocations += vertices.reserve(pixels);
    allocations += normals.reserve(pixels);
    allocations += direction.reserve(pixels);
    allocations += quadrics.reserve(pixels);
    allocations += curvature.reserve(pixels);
    allocations += status.reserve(pixels);
    if (pattern_size > kParameterPatternCapacity) allocations += pattern.reserve(pattern_size);
  }
};

CudaQuadricFit::CudaQuadricFit(const QuadricParams& params, CudaPrecision precision)
    : params_(params), precision_(precision), device_(std::make_unique<Device>()) {
  params_.validate();
}

CudaQuadricFit::~CudaQuadricFit() = default;

QuadricMap CudaQuadricFit::estimate(const VertexMap& vertices) const {
  return fit(vertices, nullptr);
}

QuadricMap CudaQuadricFit::estimate(const VertexMap& vertices, const NormalMap& normals) const {
  if (normals.width() != vertices.width() || normals.height() != vertices.height())
    throw std::invalid_argument("CudaQuadricFit: normal map and vertex map differ in size");
  return fit(vertices, &normals);
}

QuadricMap CudaQuadricFit::fit(const VertexMap& vertices, const NormalMap* normals) const {
  const int width = vertices.width(), height = vertices.height();
  const std::size_t pixels = vertices.size();
  if (pixels == 0) return QuadricMap(width, height);
  const NeighbourhoodPattern pattern = params_.pattern_for(width);
  const std::size_t pattern_size = pattern.offsets.size();

  std::lock_guard<std::mutex> lock(mutex_);
  Device& d = *device_;
  const DeviceScope scope(d.device);
  const DrainOnUnwind drain(d.stream);
  d.reserve(pixels, pattern_size);
  const cudaStream_t stream = d.stream;
  d.record(0);
  upload(d.vertices, vertices.data(), pixels, stream);
  if (normals != nullptr) upload(d.normals, normals->data(), pixels, stream);
  if (pattern_size > kParameterPatternCapacity)
    upload(d.pattern, pattern.offsets.data(), pattern_size, stream);
  if (d.poison_outputs) {
    poison(d.quadrics, pixels, stream);
    poison(d.curvature, pixels, stream);
    poison(d.direction, pixels, stream);
    poison(d.status, pixels, stream);
  }
  d.record(1);

  const VertexView view{d.vertices.data(), width, height};
  if (normals == nullptr) {
    plane_normals<<<grid_for(view), dim3(kBlockWidth, kBlockHeight), 0, stream>>>(
        view, params_.normals, d.normals.data());
    JPCR_CUDA_CHECK_LAUNCH("plane_normals", stream);
  }
  d.record(2);

  const QuadricMapView out{d.quadrics.data(), d.curvature.data(), d.direction.data(),
                           d.status.data()};
  if (precision_ == CudaPrecision::kDouble)
    launch_quad_it<double>(pattern, d.pattern, view, d.normals.data(), params_.fit, out, stream);
  else
    launch_quad_it<float>(pattern, d.pattern, view, d.normals.data(), params_.fit, out, stream);
  d.record(3);

  QuadricMap map(width, height);  // the host allocation overlaps the kernel
  // Destroyed before `map`: an exception below waits for the copies into it first (they return
  // early into pinned memory, where a copy after the free would write freed memory).
  const DrainOnUnwind drain_into_map(stream);
  if (d.poison_outputs) {
    poison(map.quadrics);
    poison(map.curvature);
    poison(map.direction);
    poison(map.status);
  }
  download(map.quadrics.data(), d.quadrics, pixels, stream);
  download(map.curvature.data(), d.curvature, pixels, stream);
  download(map.direction.data(), d.direction, pixels, stream);
  download(map.status.data(), d.status, pixels, stream);
  d.record(4);
  JPCR_CUDA_CHECK(cudaStreamSynchronize(stream));
  d.timing = {d.elapsed_ms(0, 1), d.elapsed_ms(1, 2), d.elapsed_ms(2, 3), d.elapsed_ms(3, 4),
              d.elapsed_ms(0, 4)};
  return map;
}

CudaQuadricFitTiming CudaQuadricFit::last_timing() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return device_->timing;
}

std::size_t CudaQuadricFit::device_allocations() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return device_->allocations;
}

void CudaQuadricFit::set_poison_outputs(bool on) {
  std::lock_guard<std::mutex> lock(mutex_);
  device_->poison_outputs = on;
}

}  // namespace jpcr
