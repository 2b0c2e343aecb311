// GPU Quad IT against the CPU reference (issue 7, label gpu; skipped without a GPU): on fresh
// random frames CudaQuadricFit equals fit_quadric_pixel<double> run on the host with the same
// normals — curvature RMS ≤ 1e-4 1/m over pixels valid in both, status equal except at ≤ 0.1 %
// of pixels (samples exactly at the gate may fall either way) — and writes every output element
// (outputs are pre-filled with a sentinel). With the normals computed on the device, at most
// max(1, pixels / 10⁵) pixels may differ by more than 1e-4 1/m (see that test). Device buffers are
// reused across frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "cuda/random_frames.hpp"
#include "jpcr/cuda/cpu_fallback_estimator.hpp"
#include "jpcr/cuda/cuda_check.hpp"
#include "jpcr/cuda/cuda_quadric_fit.hpp"
#include "jpcr/cuda/curvature_estimator_factory.hpp"

namespace jpcr {
namespace {

#define SKIP_WITHOUT_GPU()      \
  if (!cuda_device_available()) \
  GTEST_SKIP() << "no CUDA device (" << query_cuda_device().description << ")"

// True when some 4-byte word (or status byte) still holds the 0xFF sentinel of poisoning.
template <typename T>
std::size_t sentinel_words(const Image<T>& image) {
  std::size_t n = 0;
  const auto* bytes = reinterpret_cast<const unsigned char*>(image.data());
  const std::size_t size = image.size() * sizeof(T);
  const std::size_t word = sizeof(T) % 4 == 0 ? 4 : 1;
  for (std::size_t i = 0; i + word <= size; i += word) {
    bool all = true;
    for (std::size_t k = 0; k < word; ++k)
      all = all && bytes[i + k] == 0xFF;
    n += all ? 1 : 0;
  }
  return n;
}

void expect_every_element_written(const QuadricMap& map) {
  EXPECT_EQ(sentinel_words(map.quadrics), 0u);
  EXPECT_EQ(sentinel_words(map.curvature), 0u);
  EXPECT_EQ(sentinel_words(map.direction), 0u);
  EXPECT_EQ(sentinel_words(map.status), 0u);
  for (std::size_t i = 0; i < map.status.size(); ++i) {
    const bool valid = map.status[i] == QuadricStatus::kValid;
    ASSERT_LE(static_cast<int>(map.status[i]), static_cast<int>(QuadricStatus::kNoStep));
    ASSERT_EQ(std::isfinite(map.curvature[i].x()), valid) << "pixel " << i;
    ASSERT_EQ(std::isfinite(map.direction[i].x()), valid) << "pixel " << i;
  }
}

struct Parity {
  double rms = 0.0;       // over the pixels valid in both
  double max = 0.0;       // the largest |Δκ|
  int over = 0;           // pixels with |Δκ| > kFlip
  double rms_rest = 0.0;  // over the others (still divided by all valid_both)
  int valid_both = 0, status_differ = 0, pixels = 0;
};

constexpr double kFlip = 1e-4;  // 1/m: the parity bound on the curvature RMS
// With the host's normals the GPU and the double reference differ by FMA contraction: κ RMS
// 7e-8 to 2.8e-7 1/m, every status equal, on all 28 random frames logged (cuda/NOTES.md; before
// Quad IT's step test compared the gated cost and retried the first step, 4e6fe3b, which can
// flip a tie differently: to be measured again on a GPU). The bounds below leave 35x on the RMS
// and one flipped pixel per 10⁵; a defect confined to a tile row (317 pixels off by 1e-3 1/m,
// RMS 8e-5 over the frame) fails them.
constexpr double kParityRms = 1e-5;  // 1/m
int flips_allowed(int pixels) {
  return std::max(1, pixels / 100000);
}

// The reference: fit_quadric_pixel<double> on the host, as tests/quadric CpuFitEqualsTheReference.
Parity compare_with_reference(const QuadricMap& gpu, const VertexMap& vertices,
                              const NormalMap& normals, const QuadricParams& params) {
  const NeighbourhoodPattern pattern = params.pattern.for_width(vertices.width());
  const VertexView view{vertices.data(), vertices.width(), vertices.height()};
  Parity p;
  p.pixels = vertices.width() * vertices.height();
  double sum = 0.0, sum_rest = 0.0, max = 0.0;
  int valid_both = 0, status_differ = 0, over = 0;
#pragma omp parallel for reduction(+ : sum, sum_rest, valid_both, status_differ, over) \
    reduction(max : max) schedule(dynamic, 4)
  for (int v = 0; v < vertices.height(); ++v) {
    for (int u = 0; u < vertices.width(); ++u) {
      Quadricd q;
      const QuadricStatus s = fit_quadric_pixel<double>(
          view, pattern.offsets.data(), pattern.size(), u, v, normals(u, v), params.fit, q);
      if (s != gpu.status(u, v)) ++status_differ;
      if (s != QuadricStatus::kValid || !gpu.valid(u, v)) continue;
      const double d2 =
          (principal_curvatures(q.a, q.b, q.c) - gpu.curvature(u, v).cast<double>()).squaredNorm();
      sum += d2;
      max = std::max(max, std::sqrt(d2));
      if (std::sqrt(d2) > kFlip)
        ++over;
      else
        sum_rest += d2;
      ++valid_both;
    }
  }
  p.valid_both = valid_both;
  p.status_differ = status_differ;
  p.over = over;
  p.max = max;
  p.rms = valid_both > 0 ? std::sqrt(sum / (2.0 * valid_both)) : NAN;
  p.rms_rest = valid_both > 0 ? std::sqrt(sum_rest / (2.0 * valid_both)) : NAN;
  return p;
}

// CpuFallback (cpu_fallback.hpp) retries the GPU after an allocation failure only: that is the
// one error cuda_check marks out_of_memory. Needs no device (the codes are cudaError_t values).
TEST(CudaCheck, OnlyAnAllocationFailureIsOutOfMemory) {
  const auto out_of_memory = [](int code) {
    try {
      cuda_check(code, "cudaMalloc(&p, n)", "here.cu", 7);
    } catch (const CudaError& e) {
      EXPECT_NE(std::string(e.what()).find("call cudaMalloc(&p, n) failed at here.cu:7"),
                std::string::npos)
          << e.what();
      return e.out_of_memory();
    }
    ADD_FAILURE() << "code " << code << " did not throw";
    return false;
  };
  EXPECT_TRUE(out_of_memory(2));     // cudaErrorMemoryAllocation
  EXPECT_FALSE(out_of_memory(1));    // cudaErrorInvalidValue
  EXPECT_FALSE(out_of_memory(700));  // cudaErrorIllegalAddress: sticky
  EXPECT_NO_THROW(cuda_check(0, "cudaFree(p)", "here.cu", 8));
}

TEST(CudaQuadricFit, MatchesTheReferenceKernelOnRandomFrames) {
  SKIP_WITHOUT_GPU();
  const std::uint64_t seed = test::test_seed();
  std::printf("seed %llu (JPCR_TEST_SEED replays it); %s\n", static_cast<unsigned long long>(seed),
              query_cuda_device().description.c_str());
  const QuadricParams params;
  CudaQuadricFit fit(params);
  fit.set_poison_outputs(true);
  // 317x239: tiles cut by the image's right and bottom edges.
  for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}, std::pair{317, 239}}) {
    for (std::uint64_t k = 0; k < 2; ++k) {
      const SyntheticFrame f = test::random_frame(seed + k, w, h);
      const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
      const NormalMap normals = estimate_normals(vertices, params.normals);
      const QuadricMap map = fit.estimate(vertices, normals);
      expect_every_element_written(map);
      const Parity p = compare_with_reference(map, vertices, normals, params);
      std::printf(
          "%dx%d frame %llu: GPU vs reference kappa RMS %.3g 1/m over %d pixels, status "
          "differs at %d of %d; kernel %.3f ms\n",
          w, h, static_cast<unsigned long long>(seed + k), p.rms, p.valid_both, p.status_differ,
          p.pixels, fit.last_timing().kernel_ms);
      EXPECT_GT(p.valid_both, p.pixels / 3) << "seed " << seed + k;
      EXPECT_LE(p.over, flips_allowed(p.pixels)) << "seed " << seed + k << ", max " << p.max;
      EXPECT_LE(p.rms_rest, kParityRms) << "seed " << seed + k;
      EXPECT_LE(p.status_differ, flips_allowed(p.pixels)) << "seed " << seed + k;
    }
  }
}

// Float (CudaPrecision::kFloat: selectable, not the default) has its own kernel instance: every
// element written, and within float's distance from the double reference. On the host, float
// against double gave κ RMS 3.8e-5 to 1.9e-3 1/m on such frames (step-acceptance flips at about
// 0.03 % of the pixels, cuda/NOTES.md); the bounds leave 10x. A wrong layout or stride fails them.
TEST(CudaQuadricFit, FloatIsWithinFloatOfTheReference) {
  SKIP_WITHOUT_GPU();
  const std::uint64_t seed = test::test_seed();
  const QuadricParams params;
  CudaQuadricFit fit(params, CudaPrecision::kFloat);
  fit.set_poison_outputs(true);
  for (const auto& [w, h] : {std::pair{320, 240}, std::pair{317, 239}}) {
    const SyntheticFrame f = test::random_frame(seed, w, h);
    const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
    const NormalMap normals = estimate_normals(vertices, params.normals);
    const QuadricMap map = fit.estimate(vertices, normals);
    expect_every_element_written(map);
    const Parity p = compare_with_reference(map, vertices, normals, params);
    std::printf("%dx%d float: kappa RMS %.3g 1/m (max %.3g), status differs at %d of %d\n", w, h,
                p.rms, p.max, p.status_differ, p.pixels);
    EXPECT_GT(p.valid_both, p.pixels / 3) << "seed " << seed;
    EXPECT_LE(p.rms, 2e-2) << "seed " << seed;
    EXPECT_LE(p.status_differ, p.pixels / 1000) << "seed " << seed;
  }
}

// Without given normals the device computes them with the CPU's plane_normal: the whole GPU path
// against estimate_normals + the reference kernel on the host. The device's normals differ from
// the host's in the last bit at 6-8 % of the pixels (FMA contraction), and plane_normal's
// eigenvector is ill-conditioned where the neighbourhood is nearly a line, so at a few pixels
// Quad IT starts from a visibly different normal and ends elsewhere: on the H200 (2026-12-04)
// one 640x480 frame of seven had a curvature RMS of 2.0e-3 1/m over all pixels: one pixel off by
// 1.54 1/m, the same in every replay (1.75e-7 without it; 1.0e-7 to 2.3e-7 on the other frames).
// So here at most max(1, pixels / 10⁵) pixels may differ by more than kFlip (1 at 320x240, 3 at
// 640x480: three times the worst seen), and the others must meet the RMS bound.
TEST(CudaQuadricFit, NormalsOnTheDeviceGiveTheSameMapAsCpuNormals) {
  SKIP_WITHOUT_GPU();
  const QuadricParams params;
  const std::uint64_t seed = test::test_seed();
  CudaQuadricFit fit(params);
  fit.set_poison_outputs(true);
  for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}}) {
    const SyntheticFrame f = test::random_frame(seed, w, h);
    const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
    const QuadricMap map = fit.estimate(vertices);
    expect_every_element_written(map);
    EXPECT_GT(fit.last_timing().normals_ms, 0.0f);
    const Parity p =
        compare_with_reference(map, vertices, estimate_normals(vertices, params.normals), params);
    std::printf(
        "%dx%d, normals on the device: kappa RMS %.3g 1/m (max %.3g; %d pixels over %.0e, RMS "
        "%.3g without them), status differs at %d of %d; normals %.3f ms, fit %.3f ms\n",
        w, h, p.rms, p.max, p.over, kFlip, p.rms_rest, p.status_differ, p.pixels,
        fit.last_timing().normals_ms, fit.last_timing().kernel_ms);
    EXPECT_GT(p.valid_both, p.pixels / 3) << "seed " << seed;
    EXPECT_LE(p.over, std::max(1, p.pixels / 100000)) << "seed " << seed;
    EXPECT_LE(p.rms_rest, kFlip) << "seed " << seed;
    EXPECT_LE(p.status_differ, p.pixels / 1000) << "seed " << seed;
  }
}

TEST(CudaQuadricFit, PatternsBeyondTheParameterBankUseGlobalMemory) {
  SKIP_WITHOUT_GPU();
  QuadricParams params;
  params.pattern = {24, 1, 160};  // about 1800 offsets at 160 px: more than a kernel parameter
  const std::uint64_t seed = test::test_seed();
  const SyntheticFrame f = test::random_frame(seed, 160, 120);
  const VertexMap vertices = compute_vertex_map(f.frame.depth, f.frame.camera);
  const NormalMap normals = estimate_normals(vertices, params.normals);
  CudaQuadricFit fit(params);
  fit.set_poison_outputs(true);
  const QuadricMap map = fit.estimate(vertices, normals);
  expect_every_element_written(map);
  const Parity p = compare_with_reference(map, vertices, normals, params);
  EXPECT_GT(p.valid_both, p.pixels / 3) << "seed " << seed;
  EXPECT_LE(p.over, flips_allowed(p.pixels)) << "seed " << seed << ", max " << p.max;
  EXPECT_LE(p.rms_rest, kParityRms) << "seed " << seed;
  EXPECT_LE(p.status_differ, flips_allowed(p.pixels)) << "seed " << seed;
}

TEST(CudaQuadricFit, ReusesDeviceBuffersAcrossFrames) {
  SKIP_WITHOUT_GPU();
  CudaQuadricFit fit;
  const std::uint64_t seed = test::test_seed();
  const SyntheticFrame a = test::random_frame(seed, 320, 240);
  const SyntheticFrame b = test::random_frame(seed + 1, 320, 240);
  fit.estimate(compute_vertex_map(a.frame.depth, a.frame.camera));
  const std::size_t after_first = fit.device_allocations();
  EXPECT_GT(after_first, 0u);
  for (int i = 0; i < 3; ++i)
    fit.estimate(compute_vertex_map(b.frame.depth, b.frame.camera));
  EXPECT_EQ(fit.device_allocations(), after_first);
  const SyntheticFrame small = test::random_frame(seed, 160, 120);
  fit.estimate(compute_vertex_map(small.frame.depth, small.frame.camera));
  EXPECT_EQ(fit.device_allocations(), after_first);
}

TEST(CudaQuadricFit, AnEmptyFrameIsAllInvalidAndFullyWritten) {
  SKIP_WITHOUT_GPU();
  const CameraIntrinsics camera = synthetic_camera(160, 120);
  CudaQuadricFit fit;
  fit.set_poison_outputs(true);
  const QuadricMap map =
      fit.estimate(compute_vertex_map(DepthImage(camera.width, camera.height, 0.0f), camera));
  expect_every_element_written(map);
  EXPECT_EQ(map.valid_count(), 0u);
  EXPECT_EQ(summarize(map).no_centre, map.status.size());
}

TEST(CudaQuadricFit, TheFactoryGivesTheGpuEstimatorForCuda) {
  SKIP_WITHOUT_GPU();
  std::ostringstream log;
  const auto estimator = make_curvature_estimator(ComputeDevice::kCuda, QuadricParams{}, log);
  EXPECT_EQ(estimator->name(), "quad-it-cuda");
  EXPECT_NE(log.str().find("-> cuda ("), std::string::npos) << log.str();
  const SyntheticFrame f = test::random_frame(test::test_seed(), 160, 120);
  const QuadricMap map = estimator->estimate(compute_vertex_map(f.frame.depth, f.frame.camera));
  EXPECT_GT(map.valid_count(), map.status.size() / 3);
  // It ran on the GPU, not on the CPU behind it.
  const auto* wrapped = dynamic_cast<const CpuFallbackEstimator*>(estimator.get());
  ASSERT_NE(wrapped, nullptr);
  EXPECT_FALSE(wrapped->on_cpu());
  EXPECT_EQ(wrapped->out_of_memory_calls(), 0);
  EXPECT_EQ(log.str().find("on the GPU"), std::string::npos) << log.str();
}

}  // namespace
}  // namespace jpcr
