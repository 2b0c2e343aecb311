// JPCR_SIMD_CLONES: a CPU function compiled twice on x86-64 GCC, for AVX2 + FMA (x86-64-v3) and
// for the baseline, the version chosen at load time by the CPU (function multi-versioning);
// elsewhere once. For the per-sample loops of the joint systems and Quad IT's per-pixel steps
// (host code only).
//
// JPCR_HAVE_X86_TARGETS: 1 where code can be compiled for x86-64-v4 and v3 by `#pragma GCC
// target` (pixel_lane_sums.cpp), to be called only where cpu_simd_level() allows.
#pragma once

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

/// The best level this CPU runs: kAvx512 for x86-64-v4, kAvx2 for x86-64-v3, else kBaseline
/// (kBaseline wherever JPCR_HAVE_X86_TARGETS is 0); capped by the environment variable
/// JPCR_SIMD (`avx512`, `avx2` or `baseline`, for comparisons; another value is reported on
/// stderr and ignored). Read once (pixel_lane_sums.cpp).
SimdLevel cpu_simd_level();

}  // namespace jpcr
