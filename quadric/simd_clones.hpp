// JPCR_SIMD_CLONES: a CPU function compiled twice on x86-64 GCC, for AVX2 + FMA (x86-64-v3) and
// for the baseline, the version chosen at load time by the CPU (function multi-versioning);
// elsewhere once. For the per-sample loops of Quad IT and the joint systems (host code only).
//
// JPCR_HAVE_X86_TARGETS: 1 where code can be compiled for x86-64-v4 and v3 by `#pragma GCC
// target` (pixel_lane_sums.cpp), to be called only where cpu_simd_level() allows.
#pragma once

#include <cstdlib>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__CUDACC__)
#define JPCR_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#define JPCR_HAVE_X86_TARGETS 1
#else
#define JPCR_SIMD_CLONES
#define JPCR_HAVE_X86_TARGETS 0
#endif

namespace jpcr {

/// The instruction sets of the functions compiled per target (pixel_lane_sums.cpp).
enum class SimdLevel { kBaseline, kAvx2, kAvx512 };

/// The best level this CPU runs: kAvx512 for x86-64-v4 (AVX-512 F, BW, CD, DQ, VL), kAvx2 for
/// x86-64-v3 (AVX2, FMA, BMI2), else kBaseline; capped by the environment variable JPCR_SIMD
/// (`avx2` or `baseline`, for comparisons). Read once.
inline SimdLevel cpu_simd_level() {
#if JPCR_HAVE_X86_TARGETS
  static const SimdLevel level = [] {
    SimdLevel best = SimdLevel::kBaseline;
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512vl"))
      best = SimdLevel::kAvx512;
    else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
             __builtin_cpu_supports("bmi2"))
      best = SimdLevel::kAvx2;
    const char* cap = std::getenv("JPCR_SIMD");
    if (cap != nullptr && std::strcmp(cap, "avx2") == 0 && best > SimdLevel::kAvx2)
      best = SimdLevel::kAvx2;
    if (cap != nullptr && std::strcmp(cap, "baseline") == 0) best = SimdLevel::kBaseline;
    return best;
  }();
  return level;
#else
  return SimdLevel::kBaseline;
#endif
}

}  // namespace jpcr
