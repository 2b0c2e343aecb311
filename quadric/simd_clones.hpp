// JPCR_SIMD_CLONES: a CPU function compiled twice on x86-64 GCC, for AVX2 + FMA (x86-64-v3) and
// for the baseline, the version chosen at load time by the CPU (function multi-versioning);
// elsewhere once. For the per-sample loops of Quad IT and the joint systems (host code only).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__CUDACC__)
#define JPCR_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define JPCR_SIMD_CLONES
#endif
